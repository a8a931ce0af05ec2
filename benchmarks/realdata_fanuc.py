"""Instrument-point calibration on real public laser-tracker data of a FANUC R-2000iC/165F.

Data: benchmarks/data/boby2021 (converted by scripts/convert_boby2021.py from the public data set of Boby
& Klimchik; 59 distinct poses, single-joint sweeps of all six joints about one configuration, three
reflectors on the end-effector). The model: calibrate/robots/r2000ic165f.urdf (datasheet dimensions, ROS-Industrial layout).

Protocols (base and tool are refitted on every validation set, paper Section 5.2):
  interleaved   fit on the even poses of every sweep, validate on the odd ones (same reflector);
  other-tool    fit on all poses of reflector N2, validate on reflectors N1 and N3 (new tool points);
and for both the nominal model as the "before". Prints a table; ``--markdown`` prints it for the docs.

    python benchmarks/realdata_fanuc.py [--markdown]
"""
from __future__ import annotations

import argparse
import logging
from pathlib import Path

from rodlab.calibrate import read_points, resolve_robot
from rodlab.calibrate.holdout import fit_and_validate, interleaved

DATA = Path(__file__).parent / "data" / "boby2021"


def run() -> list:
    """The interleaved split of each reflector, then fit on N2 and validate on N1 and N3."""
    robot = resolve_robot("r2000ic165f")
    pts = {n: read_points(DATA / f"r2000ic_{n}.validation.csv") for n in ("N1", "N2", "N3")}
    rows = []
    for name, p in pts.items():
        fit, test = interleaved(p)
        rows += fit_and_validate(robot, "interleaved", fit, [(name + " odd poses", test)])
    rows += fit_and_validate(robot, "other tool", pts["N2"], [("N1", pts["N1"]), ("N3", pts["N3"])])
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--markdown", action="store_true")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    rows = run()
    if a.markdown:
        print("| protocol | validated on | fit / test points | fit rms [mm] | nominal mean / max [mm] | "
              "calibrated mean / max [mm] | time [s] |")
        print("|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r.protocol} | {r.test} | {r.fit_points} / {r.test_points} | {r.fit_rms_mm:.3f} | "
                  f"{r.before.mean_mm:.3f} / {r.before.max_mm:.3f} | {r.after.mean_mm:.3f} / "
                  f"{r.after.max_mm:.3f} | {r.seconds:.2f} |")
    else:
        for r in rows:
            print(f"{r.protocol:<12} {r.test:<14} fit {r.fit_points:3d} rms {r.fit_rms_mm:.3f} mm | "
                  f"nominal mean {r.before.mean_mm:.3f} max {r.before.max_mm:.3f} | calibrated mean "
                  f"{r.after.mean_mm:.3f} max {r.after.max_mm:.3f} mm | {r.seconds:.2f} s | held "
                  f"{', '.join(r.held)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
