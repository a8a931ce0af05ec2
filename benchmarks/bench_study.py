"""Benchmark: `rodlab study` at scale — 100 designs x 4 methods on a fresh cache, on the local Dask cluster (2
workers), as a user runs it (the CLI command, imports included): the default linear predictor (goal <= 60 s on
2 cores) and `--monte-carlo` with 20 replicates (the linear one >= 8x faster).

    python benchmarks/bench_study.py            # writes docs/benchmarks/study.md
"""
from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from pages import write_page  # noqa: E402

GOAL_S = 600.0
L1, L2 = "150:600:50", "300:750:50"          # 10 x 10 designs around rod 1#
REPLICATES, WORKERS = 20, 2


def _run(out: Path, monte_carlo: bool = True) -> float:
    mc = ["--monte-carlo", "--replicates", str(REPLICATES)] if monte_carlo else []
    cmd = ["rodlab", "study", "rod1", "--L1", L1, "--L2", L2, *mc, "--workers", str(WORKERS), "-q", "-o", str(out)]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, stdout=subprocess.PIPE)
    return time.perf_counter() - t0


def main() -> None:
    import pandas as pd
    tmp = Path(tempfile.mkdtemp(prefix="bench-study-"))
    try:
        linear = _run(tmp / "lin", monte_carlo=False)
        cold = _run(tmp / "s")
        warm = _run(tmp / "s")                                   # everything cached: the resume path
        df = pd.read_csv(tmp / "s" / "study.csv")
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    designs = df["design"].nunique()
    usable = int((df.drop_duplicates("design")["status"] == "ok").sum())
    tasks = designs * (1 + REPLICATES)
    lines = ["# Benchmark: rodlab study at scale", "",
             f"`python benchmarks/bench_study.py` on {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}; the environment it runs in (see below).", "",
             f"`rodlab study rod1 --L1 {L1} --L2 {L2} --replicates {REPLICATES} --workers {WORKERS}`: {designs} designs "
             f"({usable} usable on the TX90), 4 methods, error budget on; one solid FEA run calibrates the family's "
             "joints first.", "",
             "| run | time [s] | goal [s] | tasks | tasks / s / worker |", "|---|---|---|---|---|",
             f"| linear predictor (default), fresh cache | {linear:.0f} | 60 | {designs} | "
             f"{designs / linear / WORKERS:.2f} |",
             f"| `--monte-carlo`, fresh cache | {cold:.0f} | {GOAL_S:.0f} | {tasks} | {tasks / cold / WORKERS:.2f} |",
             f"| `--monte-carlo`, everything cached (resume) | {warm:.1f} | | 0 | |", "",
             f"The linear predictor is {cold / linear:.1f}x faster than Monte Carlo on these designs (goal >= 8x).",
             "",
             f"A replicate task (one simulated campaign calibrated 5 times and validated 6 times) runs at about "
             f"{tasks / cold / WORKERS:.2f} tasks per second per worker here: a cluster of W workers does this study in "
             f"~{cold * WORKERS:.0f} / W s."]
    write_page(HERE.parent / "docs" / "benchmarks" / "study.md", lines, HERE / "study_notes.md")


if __name__ == "__main__":
    main()
