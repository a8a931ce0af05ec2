"""The comparison table of docs/study.md ("With the robot's own error and the rod's slip"): predicted means of
`rodlab study rod1 .. rod6` runs against the paper's Table 3, the residual of every published number.

    rodlab study rod1 rod2 rod3 rod4 rod5 rod6 --robot tx90 --robot-floor-mm 0.263 -o paper-floor
    rodlab study rod1 rod2 rod3 rod4 rod5 rod6 --robot tx90 --robot-floor-mm 0.263 --monte-carlo -o paper-floor-mc
    python scripts/table3_compare.py paper-floor [paper-floor-mc]        # markdown on stdout
"""
from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

#: Table 3 mean positioning error after calibration [mm] (Calc published for the steel rods only)
TABLE3 = {"1#": {"none": 0.302, "fea": 0.276, "meas": 0.274}, "2#": {"none": 0.312, "fea": 0.290, "meas": 0.286},
          "3#": {"none": 0.414, "fea": 0.364, "meas": 0.362},
          "4#": {"none": 0.475, "calc": 0.467, "fea": 0.450, "meas": 0.451},
          "5#": {"none": 0.392, "calc": 0.404, "fea": 0.372, "meas": 0.371},
          "6#": {"none": 0.601, "calc": 0.522, "fea": 0.505, "meas": 0.507}}
ORDER = ("none", "calc", "fea", "meas")


def _res(pred: float, paper: float) -> str:
    return f"{100 * (pred / paper - 1):+.0f}%"


def main(argv: list[str]) -> int:
    if not argv or len(argv) > 2:
        print(__doc__)
        return 2
    lin = pd.read_csv(Path(argv[0]) / "study.csv")
    mc = pd.read_csv(Path(argv[1]) / "study.csv") if len(argv) > 1 else None
    head = "| rod | method | predicted mean [90 % band] mm | Table 3 mean mm | residual |"
    if mc is not None:
        head += " Monte Carlo mean [90 % band] mm | residual |"
    print(head)
    print("|---" * (head.count("|") - 1) + "|")
    worst = {}
    for rod, methods in TABLE3.items():
        for m in ORDER:
            if m not in methods:
                continue
            r = lin[(lin.design == rod) & (lin.method == m)].iloc[0]
            paper = methods[m]
            row = (f"| {rod} | {m} | {r.mean_mm:.3f} [{r.mean_p05_mm:.3f}-{r.mean_p95_mm:.3f}] | {paper:.3f} | "
                   f"{_res(r.mean_mm, paper)} |")
            worst.setdefault(m, []).append(abs(r.mean_mm / paper - 1))
            if mc is not None:
                s = mc[(mc.design == rod) & (mc.method == m)].iloc[0]
                row += f" {s.mean_mm:.3f} [{s.mean_p05_mm:.3f}-{s.mean_p95_mm:.3f}] | {_res(s.mean_mm, paper)} |"
            print(row)
    print()
    print("worst |residual| per method (linear predictor): "
          + ", ".join(f"{m} {100 * max(v):.1f} %" for m, v in worst.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
