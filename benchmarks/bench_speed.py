"""Benchmark: what a user runs, timed as they run it (the CLI with its defaults, imports included), in the
environment README command 1 creates, against the goals of the fresh-machine speed issue.

    python benchmarks/bench_speed.py            # prints and writes docs/benchmarks/speed.md (~3 min)
    python benchmarks/bench_speed.py --quick    # skips the demo

Each command runs in a fresh process (wall time, and the peak memory of that process). The campaign used by
``plan`` and ``calibrate`` is simulated first by ``rodlab simulate-campaign``, so nothing outside the
repository is needed. The library cycle (simulate + identify + validate, 30 points, compensation on) is
timed in-process, median of 5, since a design study runs thousands of them in one process.
"""
from __future__ import annotations

import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
from pages import user_env, write_page  # noqa: E402  (beside this script, on sys.path when it runs)
OUT = ROOT / "docs" / "benchmarks" / "speed.md"


def _run(args: list[str], cwd: Path, cache: Path) -> tuple[float, float, str]:
    """Wall time [s], peak RSS of that child process [GB], and the last output line of ``rodlab ARGS`` (mesh
    cache folder ``cache``)."""
    with tempfile.TemporaryFile("w+") as out:
        t0 = time.perf_counter()
        p = subprocess.Popen([sys.executable, "-m", "rodlab", "-q", *args], cwd=cwd, stdout=out,
                             stderr=subprocess.STDOUT, text=True, env=user_env(RODLAB_CACHE_DIR=str(cache)))
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.perf_counter() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        text = out.read()
    if p.returncode not in (0, 3):
        raise SystemExit(f"rodlab {' '.join(args)} failed ({p.returncode}):\n{text}")
    lines = [ln for ln in text.splitlines() if ln.strip()]
    return wall, usage.ru_maxrss / 1e6, lines[-1] if lines else ""


def _cycle_seconds(tmp: Path) -> tuple[float, float]:
    """Median seconds of one simulate + identify + validate cycle (30 points, compensation on), and its
    validation mean [mm]."""
    import numpy as np

    from rodlab import calc_rod_compliance, resolve_design
    from rodlab.calibrate import (campaign_observations, identify, read_campaign, read_fixture, read_points,
                                  resolve_robot, Rod, RodDeflection, validate)
    from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
    robot, rod = resolve_robot("tx90"), calc_rod_compliance(resolve_design("rod1"))
    times, means = [], []
    for seed in range(5):
        out = tmp / f"cycle{seed}"
        t0 = time.perf_counter()
        simulate_campaign(robot, rod, out, CampaignSpec(seed=seed, validation_points=30))
        obs = campaign_observations(read_campaign(out / "multical.campaign.csv"),
                                    read_fixture(out / "multical.fixture.json"), rod)
        res = identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod)])
        stats = validate(robot, res.params, read_points(out / "multical.validation.csv"))[0]
        times.append(time.perf_counter() - t0)
        means.append(stats.mean_mm)
    return float(np.median(times)), float(np.median(means))


#: the row that reruns the one before it with that row's mesh cache (every other row starts with an empty cache)
RERUN = "solid FEA of rod 1#, defaults, rerun (mesh cached)"
ROWS = [  # (what, args, goal, goal seconds)
    ("solid FEA of rod 1#, no error estimate", ["fea", "rod1", "--model", "solid", "--no-error-estimate", "-o",
                                                "rod1.fea.json"],
     "library <= 5 s from the design (fea.md: 1.1-1.3 s); the command adds its imports", None),
    ("solid FEA of rod 1#, defaults (+ recovery error estimate)", ["fea", "rod1", "--model", "solid", "-o",
                                                                   "rod1.fea2.json"], "<= 4 s, <= 1 GB", 4.0),
    (RERUN, ["fea", "rod1", "--model", "solid", "-o", "rod1.fea3.json"], "-", None),
    ("simulate-campaign (5 x 6, TX90)", ["simulate-campaign", "--rod", "rod1.fea.json", "-o", "camp"],
     "<= 3 s", 3.0),
    ("plan (k 6, 30 candidates per position)", ["plan", "--fixture", "camp/multical.fixture.json", "--rod",
                                                "rod1.fea.json", "-o", "plan.csv"], "<= 3 s", 3.0),
    ("calibrate (30 points, compensation fea)", ["calibrate", "camp/multical.campaign.csv", "--fixture",
                                                 "camp/multical.fixture.json", "--rod", "rod1.fea.json",
                                                 "--validate", "camp/multical.validation.csv"], "-", None),
    ("rig simulate (default plan: 0.5-1.5 kg on the carbon rod 1#)",
     ["rig", "simulate", "--sim", "rod1.fea.json", "--effect", "friction:F_f_N=0.1", "-o", "rec.rig.csv"], "-", None),
    ("diagnose --rig (one recording)", ["diagnose", "--rig", "rec.rig.csv", "--sim", "rod1.fea.json"],
     "<= 1 s per recording", 1.0),
    ("sweep --calibrate (13 x 15 grid)", ["sweep", "--L1", "150:450:25", "--L2", "300:650:25", "--calibrate",
                                          "--serial", "-o", "sweep.csv"], "~5-10 s (README before)", None),
    ("demo", ["demo", "-o", "demo"], "<= 15 s", 15.0),
    ("study, 10 x 10 grid, 4 methods (linear predictor, 2 workers)",
     ["study", "rod1", "--L1", "150:600:50", "--L2", "300:750:50", "--robot", "tx90", "-o", "study"], "<= 60 s", 60.0),
]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="skip the demo")
    ap.add_argument("--no-write", action="store_true", help="print only")
    args = ap.parse_args()
    from rodlab.fea.solver import available_backend
    rows = []
    with tempfile.TemporaryDirectory(prefix="rodlab-speed-") as d:
        tmp = Path(d)
        for i, (what, cmd, goal, limit) in enumerate(ROWS):
            if args.quick and cmd[0] == "demo":
                continue
            cache = tmp / f"cache-{i - 1 if what == RERUN else i}"
            wall, gb, last = _run(cmd, tmp, cache)
            verdict = "" if limit is None else ("met" if wall <= limit else f"missed by {wall - limit:.1f} s")
            rows.append((what, f"`rodlab {' '.join(cmd)}`", wall, gb, goal, verdict))
            print(f"{what:<55} {wall:7.2f} s {gb:5.2f} GB  {goal} {verdict}", flush=True)
        cyc, mean = _cycle_seconds(tmp)
        rows.append(("simulate + identify + validate cycle (library, 30 points)", "in-process, median of 5", cyc,
                     float("nan"), "<= 1 s", "met" if cyc <= 1.0 else f"missed by {cyc - 1.0:.2f} s"))
        print(f"cycle {cyc:.2f} s (validation mean {mean * 1e3:.1f} um)")
    if args.no_write:
        return 0
    lines = ["# Speed of what a user runs (fresh venv, README command 1)", "",
             f"Generated by `python benchmarks/bench_speed.py` on {time.strftime('%Y-%m-%d')}, "
             f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; sparse solver "
             f"`{available_backend()}`. Wall time of the whole command in a fresh process (imports included), "
             "peak memory of that process. One run each: compare rows of one run, not across runs (shared VMs).",
             "", "| what | command | wall [s] | peak [GB] | goal | |", "|---|---|---:|---:|---|---|"]
    for what, cmd, wall, gb, goal, verdict in rows:
        lines.append(f"| {what} | {cmd} | {wall:.2f} | {'' if gb != gb else f'{gb:.2f}'} | {goal} | {verdict} |")
    write_page(OUT, lines, ROOT / "benchmarks" / "speed_notes.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
