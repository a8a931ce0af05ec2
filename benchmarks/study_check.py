"""Check: does the in-memory accuracy predictor give what users get from files and `rodlab calibrate`?

For five designs on the TX90: the prediction from ten replicates (seeds 0-9), and ten independent campaigns of
the same priors (seeds 1000-1009) written as the contract's files (campaign, fixture, validation, one
compliance file per method) and calibrated end to end by the `rodlab calibrate --validate` command (in this
process); the mean of the end-to-end validation means is compared with the predicted mean and its 90 % band.

    python benchmarks/study_check.py            # writes docs/benchmarks/study_check.md
"""
from __future__ import annotations

import json
import os
import platform
import sys
import tempfile
import time
from contextlib import redirect_stderr, redirect_stdout
from io import StringIO
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from pages import write_page  # noqa: E402

REPLICATES = 10
#: the end-to-end campaigns use other seeds than the prediction: independent draws of the same priors
INDEPENDENT = 1000
METHODS = ("none", "fea", "meas")


def _designs():
    from dataclasses import replace

    from rodlab.core.design_io import resolve_design
    d4 = resolve_design("rod4")
    return [resolve_design("rod1"), resolve_design("rod3"), d4, resolve_design("rod6"),
            replace(d4, L1_mm=250.0, L2_mm=550.0, name="4# 250-550")]


def _end_to_end(folder: Path, method: str) -> float:
    from rodlab.app.cli.main import main
    rod = folder / ("fea.compliance.json" if method == "none" else f"{method}.compliance.json")
    argv = ["calibrate", str(folder / "campaign.csv"), "--fixture", str(folder / "fixture.json"), "--rod", str(rod),
            "--validate", str(folder / "validation.csv"), "--json", str(folder / f"{method}.result.json"), "-q"]
    if method == "none":
        argv += ["--compensation", "none"]
    with redirect_stdout(StringIO()), redirect_stderr(StringIO()):
        rc = main(argv)
    if rc not in (0, 3):
        raise RuntimeError(f"rodlab calibrate exited {rc} on {folder}")
    return json.loads((folder / f"{method}.result.json").read_text())["validation"]["after"]["mean_mm"]


def main() -> None:
    from rodlab.core.calc import calc_rod_compliance
    from rodlab.calibrate import Rod, resolve_robot
    from rodlab.calibrate.plan import plan_poses
    from rodlab.calibrate.predict import Priors, run_replicate, simulate_replicate, summarise
    from rodlab.calibrate.replicate_io import write_replicate
    from rodlab.calibrate.simulate import standard_base, standard_fixture
    from rodlab.fea import compute_compliance
    from rodlab.app.study import r_prior_of
    robot, fixture, base = resolve_robot("tx90"), standard_fixture(), standard_base()
    lines = ["# Check: predicted accuracy vs end-to-end `rodlab calibrate` on the same draws", "",
             f"`python benchmarks/study_check.py` on {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}. {REPLICATES} replicates per design; the "
             "end-to-end column is the mean over 10 *other* campaigns of the same priors (seeds 1000-1009), each written "
             "as contract files and calibrated by `rodlab calibrate --validate` (frame compliance with its global "
             "calibration).", "",
             "| design | method | predicted mean [90 % band] mm | end to end mean mm | inside the band |",
             "|---|---|---|---|---|"]
    inside = 0
    total = 0
    for d in _designs():
        fea, calc = compute_compliance(d, "frame"), calc_rod_compliance(d)
        q, _ = plan_poses(robot, fixture, Rod.rigid(d.tool_mm, fea.mass_kg, fea.com_T_mm))
        plan = {j: np.deg2rad(v) for j, v in q.items()}
        pri = Priors(r_rod=r_prior_of(d))
        outs = [run_replicate(robot, plan, fixture, base, fea, calc, METHODS, pri, s, budget=False)
                for s in range(REPLICATES)]
        e2e = {m: [] for m in METHODS}
        with tempfile.TemporaryDirectory() as tmp:
            for s in range(REPLICATES):
                folder = Path(tmp) / f"rep{s}"
                sim = simulate_replicate(robot, plan, fixture, base, fea, calc, METHODS, pri, INDEPENDENT + s)
                write_replicate(sim, fixture, fea, folder)
                for m in METHODS:
                    e2e[m].append(_end_to_end(folder, m))
        for a in summarise(outs, METHODS):
            got = float(np.mean(e2e[str(a.method)]))
            ok = a.mean_p05_mm <= got <= a.mean_p95_mm
            inside += ok
            total += 1
            lines.append(f"| {d.name} | {a.method} | {a.mean_mm:.4f} [{a.mean_p05_mm:.4f}-{a.mean_p95_mm:.4f}] | "
                         f"{got:.4f} | {'yes' if ok else 'NO'} |")
        print(d.name, "done", flush=True)
    lines += ["", f"{inside} of {total} end-to-end means lie inside the predicted band."]
    write_page(HERE.parent / "docs" / "benchmarks" / "study_check.md", lines, HERE / "study_check_notes.md")


if __name__ == "__main__":
    main()
