"""Benchmark: the frame model joint-calibrated on one solid run (fea.joints) - cost and accuracy.

    python benchmarks/bench_joints.py          # ~2 min; writes docs/benchmarks/joints.md

- cost of the calibration run: the solid FEA of rod 1# with the three tip-moment cases and the displacements
  kept, against the plain six-case run (median of 3 each), and the section extraction;
- the joint-calibrated frame per design and a 1000-design sweep on Dask (goal of the frame: <= 5 ms per design,
  <= 30 s for 1000 designs);
- accuracy on the paper's two families against their stored solid references (fea/data/solid_reference.json),
  next to the global frame.
"""
from __future__ import annotations

import os
import platform
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
OUT = ROOT / "docs" / "benchmarks" / "joints.md"
FAMILIES = {"rod1": {"rod2": None, "rod3": None, "rod1_L1_200_L2_600": (200.0, 600.0)},
            "rod4": {"rod5": None, "rod6": None, "rod4_L1_420_L2_330": (420.0, 330.0)}}


def _err(C, ref) -> float:
    import numpy as np
    out = []
    for mine, r in zip(C, ref):
        r = np.asarray(r)
        big = np.abs(r) > 0.02 * np.abs(r).max()
        out.append(np.abs(mine[big] / r[big] - 1).max())
    return float(max(out))


def _cost(d1):
    """Median of 3 solid runs of each kind and the section extraction: (lines, the joint calibration)."""
    from rodlab.fea import solid_compliance
    from rodlab.fea.joints import joints_from_motions, measure_sections
    from rodlab.geometry import mesh_rod
    solid_compliance(d1, mesh_rod, error_estimate=False)                 # imports, first gmsh call
    times = {}
    for label, kw in (("six load cases", {}), ("nine, displacements kept", {"tip_moments": True,
                                                                             "keep_displacements": True})):
        runs = []
        for _ in range(3):
            t0 = time.perf_counter()
            _, res = solid_compliance(d1, mesh_rod, error_estimate=False, **kw)
            runs.append(time.perf_counter() - t0)
        times[label] = statistics.median(runs)
    t0 = time.perf_counter()
    sec, tip, margins = measure_sections(d1, res)
    jc = joints_from_motions(d1, sec, tip, margins)
    t_cal = time.perf_counter() - t0
    lines = ["## Cost of the calibration", "",
             "| rod 1#, solid FEA from the design (median of 3) | wall s |", "|---|---|"]
    lines += [f"| {k} | {v:.2f} |" for k, v in times.items()]
    lines += [f"| section motions and corrections (after the solve) | {t_cal:.2f} |", ""]
    return lines, jc


def _evaluation(d1, jc) -> list[str]:
    """Per-design time of the global and the joint-calibrated frame (mean of 300), and a 1000-design sweep."""
    import numpy as np
    from rodlab.fea.frame import frame_compliance
    from rodlab.fea.joints import joint_frame_compliance
    from rodlab.fea.sweep import run_sweep
    m = replace(d1, L1_mm=250.0, L2_mm=500.0, name="1# 250-500")
    per = {}
    for label, f in (("global frame", lambda: frame_compliance(m)),
                     ("joint-calibrated frame", lambda: joint_frame_compliance(m, jc))):
        f()
        t0 = time.perf_counter()
        for _ in range(300):
            f()
        per[label] = (time.perf_counter() - t0) / 300 * 1e3
    t0 = time.perf_counter()
    df = run_sweep(d1, np.linspace(150, 450, 40), np.linspace(300, 650, 25), model="frame", workers=2, batch=50,
                   calibration=jc)
    t_sweep = time.perf_counter() - t0
    return ["## Evaluation", "",
            "".join(f"- {k}: {v:.2f} ms per design\n" for k, v in per.items())
            + f"- {len(df)}-design joint-calibrated sweep on a 2-worker Dask LocalCluster: {t_sweep:.1f} s "
              f"including the cluster start ({int((df['status'] == 'ok').sum())} valid designs)", ""]


def _accuracy() -> list[str]:
    """Each family calibrated on its base's solid run, against each member's own solid FEA (the built-in rods
    today; ``fea/data/solid_reference.json`` holds the rods of before #45, which the tests use)."""
    from rodlab import resolve_design
    from rodlab.fea import solid_compliance
    from rodlab.fea.frame import frame_compliance
    from rodlab.fea.joints import joint_frame_compliance, joints_from_motions, measure_sections
    from rodlab.geometry import mesh_rod
    lines = ["## Accuracy on the paper's families", "",
             "Largest relative error over every entry above 2 % of its matrix's largest, C_F and C_g, against each "
             "member's own solid FEA (default half model, computed here).", "",
             "| calibrated on (one solid run) | member | free pipe I / II mm | joint-calibrated | global frame |",
             "|---|---|---|---|---|"]
    for base, members in FAMILIES.items():
        b = resolve_design(base)
        _, res = solid_compliance(b, mesh_rod, error_estimate=False, tip_moments=True, keep_displacements=True)
        jcb = joints_from_motions(b, *measure_sections(b, res))
        for name, L in dict({base: None}, **members).items():
            dm = resolve_design(name) if L is None else replace(b, L1_mm=L[0], L2_mm=L[1], name=name)
            own, _ = solid_compliance(dm, mesh_rod, error_estimate=False)
            ref = (own.C_F, own.C_g)
            lines.append(f"| {b.name} (sections {jcb.margins_mm[0]:g} / {jcb.margins_mm[1]:g} mm in) | {name} | "
                         f"{dm.pipe_I_free_mm():.0f} / {dm.pipe_II_free_mm():.0f} | "
                         f"{100 * _err(joint_frame_compliance(dm, jcb), ref):.3f} % | "
                         f"{100 * _err(frame_compliance(dm), ref):.3f} % |")
    return lines


def main() -> int:
    from rodlab import resolve_design
    from rodlab.core.fileio import atomic_write_text
    lines = ["# Benchmark: joint-calibrated frame", "",
             f"`python benchmarks/bench_joints.py` on {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}.", ""]
    d1 = resolve_design("rod1")
    cost, jc = _cost(d1)
    lines += cost + _evaluation(d1, jc) + _accuracy()
    lines += ["", "Random families (10 of the global frame's worst, both L1 / L2 variants): "
              "`python scripts/frame_random_blind.py` (docs/fea.md).", ""]
    atomic_write_text(OUT, "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
