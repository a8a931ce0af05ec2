"""Benchmark: the study's linear predictor (the default) against Monte Carlo (`rodlab study --monte-carlo`) on
the same designs — the paper's six rods and a 10-design L1 x L2 grid around rod 1#, TX90, 4 methods.

    python benchmarks/study_fast_vs_mc.py --cache /tmp/fvm --only paper   # computes (and caches) one part
    python benchmarks/study_fast_vs_mc.py --cache /tmp/fvm --only grid
    python benchmarks/study_fast_vs_mc.py --cache /tmp/fvm                # the page from the cache
                                                                         # -> docs/benchmarks/study_fast_vs_mc.md

Both run through :func:`rodlab.app.study.run_study` on a local Dask cluster (2 workers) with the same setups
(compliance, planned campaign); the families' joint calibrations are solved first and cached, outside the
timings. Agreement per design and method: the linear predictor's mean error, band ends and max against the
Monte-Carlo's, judged against 10 % and against Monte Carlo's own standard error (the spread of its replicates'
mean errors / sqrt(replicates)).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from pages import write_page  # noqa: E402

REPLICATES, DRAWS, WORKERS = 20, 256, 2
GRID_L1, GRID_L2 = [200.0, 450.0], [350.0, 450.0, 550.0, 650.0, 750.0]
PARTS = ("paper", "grid")


def _candidates(part: str):
    from rodlab.app.study import grid_candidates, list_candidates
    from rodlab.core.design_io import resolve_design
    if part == "paper":
        return list_candidates([resolve_design(f"rod{i}") for i in range(1, 7)]), False
    return grid_candidates(resolve_design("rod1"), GRID_L1, GRID_L2), True


def _run_part(part: str, cache: Path, keep: dict | None = None) -> dict:
    from rodlab.app.study import StudySpec, run_study, study_table
    from rodlab.app.study.family import family_joints
    from rodlab.calibrate import resolve_robot
    from rodlab.calibrate.simulate import standard_fixture
    robot, fixture = resolve_robot("tx90"), standard_fixture()
    cands, grid = _candidates(part)
    joints, _ = family_joints(cands, grid, True, cache / "joints")
    out = dict(keep or {})
    for name, mc in (("fast", False), ("mc", True)):
        if name in out:
            continue
        spec = StudySpec(replicates=REPLICATES, monte_carlo=mc, draws=DRAWS)
        t0 = time.perf_counter()
        run = run_study(cands, robot, fixture, spec, joints, cache / part / name, workers=WORKERS)
        elapsed = time.perf_counter() - t0
        df = study_table(run)
        if mc:                                                   # MC standard error of each mean
            se = {}
            for s, outs in zip(run.setups, run.outcomes):
                for m in spec.methods:
                    means = [o.stats[k].mean_mm for o in outs for k in o.stats if str(k) == m]
                    se[f"{s.label}|{m}"] = float(np.std(means, ddof=1) / np.sqrt(len(means))) if len(means) > 1 \
                        else float("nan")
            df["mc_se_mm"] = [se.get(f"{d}|{m}", np.nan) for d, m in zip(df["design"], df["method"])]
        out[name] = {"seconds": elapsed, "table": json.loads(df.to_json(orient="records"))}
    (cache / f"{part}.json").write_text(json.dumps(out))
    return out


def _rows(part: str, res: dict) -> tuple[list[str], list[dict]]:
    import pandas as pd
    f = pd.DataFrame(res["fast"]["table"])
    m = pd.DataFrame(res["mc"]["table"])
    key = ["design", "method"]
    j = f[f["method"].notna()].merge(m[m["method"].notna()], on=key, suffixes=("_f", "_m"))
    lines = ["| design | method | mean mm: linear / MC (+- MC SE) | 5 % | 95 % | max | mean diff | within |",
             "|---|---|---|---|---|---|---|---|"]
    stats = []
    for r in j.itertuples():
        d = r.mean_mm_f / r.mean_mm_m - 1
        ok10 = abs(d) <= 0.10
        ok_se = abs(r.mean_mm_f - r.mean_mm_m) <= 2 * r.mc_se_mm
        within = "10 %" if ok10 else ("2 SE" if ok_se else "**no**")
        band = [(getattr(r, f"{c}_f"), getattr(r, f"{c}_m")) for c in ("mean_p05_mm", "mean_p95_mm", "max_mm")]
        lines.append(f"| {r.design} | {r.method} | {r.mean_mm_f:.4f} / {r.mean_mm_m:.4f} (+-{r.mc_se_mm:.4f}) | "
                     + " | ".join(f"{a:.3f} / {b:.3f}" for a, b in band) + f" | {100 * d:+.1f} % | {within} |")
        stats.append({"part": part, "method": r.method, "mean": d, "ok10": ok10, "ok_se": ok_se,
                      **{c: a / b - 1 for c, (a, b) in zip(("p05", "p95", "max"), band)},
                      "share_f": r.share_deflection_f, "share_m": r.share_deflection_m})
    return lines, stats


def _recommendations(res: dict) -> tuple[str, str]:
    import pandas as pd

    from rodlab.app.study import recommend
    cols = ["design", "L1_mm", "L2_mm", "status", "message", "method", "mean_mm", "mean_p05_mm", "mean_p95_mm",
            "mass_kg", "c_rod_um"]
    return tuple(recommend(pd.DataFrame(res[k]["table"])[cols]).text for k in ("fast", "mc"))


def _summary(stats: list[dict]) -> list[str]:
    import pandas as pd
    s = pd.DataFrame(stats)
    lines = ["| part | method | mean: median / worst rel. diff | within 10 % | within 10 % or 2 MC SE | "
             "5 % end: median / worst | 95 % end | max |", "|---|---|---|---|---|---|---|---|"]
    for (part, method), g in s.groupby(["part", "method"], sort=False):
        def mw(c):
            v = g[c].to_numpy()
            return f"{100 * np.median(v):+.1f} / {100 * v[np.argmax(np.abs(v))]:+.1f} %"
        lines.append(f"| {part} | {method} | {mw('mean')} | {int(g['ok10'].sum())}/{len(g)} | "
                     f"{int((g['ok10'] | g['ok_se']).sum())}/{len(g)} | {mw('p05')} | {mw('p95')} | {mw('max')} |")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cache", required=True, help="folder for the results (a part computed once is read back)")
    ap.add_argument("--only", choices=PARTS, default=None, help="compute this part only (no page)")
    ap.add_argument("--redo-fast", action="store_true",
                    help="recompute the linear predictor (its cache cleared), keep the Monte-Carlo results")
    a = ap.parse_args()
    cache = Path(a.cache)
    cache.mkdir(parents=True, exist_ok=True)
    parts = [a.only] if a.only else list(PARTS)
    res = {}
    for p in parts:
        f = cache / f"{p}.json"
        old = json.loads(f.read_text()) if f.exists() else None
        if old is not None and a.redo_fast:
            import shutil
            shutil.rmtree(cache / p / "fast", ignore_errors=True)
            old = _run_part(p, cache, {"mc": old["mc"]})
        res[p] = old if old is not None else _run_part(p, cache)
    if a.only:
        return
    lines = ["# Benchmark: the study's linear predictor against Monte Carlo", "",
             f"`python benchmarks/study_fast_vs_mc.py` on {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}. TX90, the simulator's five clamping "
             f"positions, 6 orientations each, 4 methods; Monte Carlo {REPLICATES} replicates per design (the "
             f"study's default before) on {WORKERS} Dask workers, the linear predictor {DRAWS} draws (in the "
             "process itself: fewer than 16 designs do not start a cluster). The same setups (joint-calibrated "
             "frame compliance, planned campaign) for both.", "",
             "Timings: the machine was shared with other jobs (load ~2-5 on 2 cores) while this ran, so the times "
             "compare the two predictors within one run only; each includes the designs' preparation (pose "
             "planning), which both need.", "",
             "| part | designs | linear [s] | Monte Carlo [s] | speed-up |", "|---|---|---|---|---|"]
    all_stats, tables = [], []
    for p in PARTS:
        n = len(_candidates(p)[0])
        tf, tm = res[p]["fast"]["seconds"], res[p]["mc"]["seconds"]
        lines.append(f"| {p} | {n} | {tf:.0f} | {tm:.0f} | {tm / tf:.1f}x |")
        t, st = _rows(p, res[p])
        tables += ["", f"### {p}: every design and method", "", *t]
        all_stats += st
    rf, rm = _recommendations(res["paper"])
    lines += ["", "## Agreement (relative difference linear / Monte Carlo - 1)", "", *_summary(all_stats), "",
              "## The recommendation on the paper's six rods", "", f"- linear: *{rf}*", f"- Monte Carlo: *{rm}*",
              *tables]
    write_page(HERE.parent / "docs" / "benchmarks" / "study_fast_vs_mc.md", lines, HERE / "study_fast_vs_mc_notes.md")


if __name__ == "__main__":
    main()
