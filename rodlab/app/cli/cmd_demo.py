"""``rodlab demo``: the main job end to end (and its HTML report)."""
from __future__ import annotations

import argparse
import sys
import time

from .argtypes import seed
from .interrupts import kill_as_interrupt

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("demo", help="run the main job end to end on built-in defaults (rod 1#, TX90)",
                       description="Rod 1# -> CAD -> FEA -> simulated rig recording with a concealed effect -> rig fit "
                                   "-> diagnosis -> simulated TX90 campaign -> calibration with every compensation "
                                   "method (Table 3) -> L1/L2 sweep (its frame joint-calibrated on the solid FEA); all files "
                                   "under the output folder.")
    p.add_argument("-o", "--output", default="out/demo", help="run folder (default out/demo)")
    p.add_argument("--seed", type=seed, default=7, help="random seed of the simulated rig and campaign (default 7)")
    p.add_argument("--no-report", action="store_true", help="do not write report.html")
    p.set_defaults(func=cmd_demo)


def cmd_demo(args: argparse.Namespace) -> int:
    from ..pipeline import STAGES, run_demo
    t0 = time.perf_counter()

    def progress(stage, msg):
        k = STAGES.index(stage) + 1
        print(f"[{k}/{len(STAGES)}] {stage:<9} {msg}", file=sys.stderr, flush=True)
    with kill_as_interrupt():                  # kill / hang-up stop the demo as Ctrl-C does: its CAD child first
        s = run_demo(args.output, progress, seed=args.seed)
    st = s["stages"]
    print(f"\nrod 1#: c_rod calc {st['design']['c_rod_um_calc']:.0f} um, {st['fea']['model']} c_rod "
          f"{st['fea']['c_rod_um']:.0f} um; rig r_rod {st['fit']['r_rod']:.3f}")
    d = st["diagnose"]
    for f in d["findings"]:
        where = f" at {f['location']}" if f["location"] else ""
        print(f"diagnosis: {d['verdict']}: {f['effect']}{where} "
              + ", ".join(f"{k} = {v:.3g}" for k, v in f["parameters"].items() if isinstance(v, float) and abs(v) > 1e-15))
    up = d.get("update")
    if up:
        print("rod as built (rodlab update -> rod1.asbuilt.rod.toml): " + ", ".join(
            f"{k.split('.', 1)[1]} {v0:.4g} -> {v:.4g} +- {s:.2g}" for k, v0, v, s in
            zip(up["keys"], up["design"], up["as_built"], up["sigma"])))
    print(f"{'method':<10} {'Mean/[mm]':>10} {'Max/[mm]':>9} {'Median/[mm]':>12} {'SD/[mm]':>8}")
    for k, v in st["calibrate"]["table3"].items():
        print(f"{k:<10} {v['mean_mm']:10.3f} {v['max_mm']:9.3f} {v['median_mm']:12.3f} {v['sd_mm']:8.3f}")
    sw = st["sweep"]["stiffest"]
    print(f"sweep: {st['sweep']['designs']} designs; stiffest L1 = {sw['L1_mm']:g}, L2 = {sw['L2_mm']:g} mm "
          f"(c_rod {sw['c_rod_um']:.0f} um)")
    print(f"study of {', '.join(st['study']['designs'])}: {st['study']['recommendation']}")
    if not args.no_report:
        from ..report import write_folder_report
        print(f"wrote {write_folder_report(args.output)}")
    print(f"done in {time.perf_counter() - t0:.0f} s; everything is in {args.output}")
    return 0
