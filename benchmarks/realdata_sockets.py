"""Ball-in-socket calibration on public real data (MUKCa: Franka Panda, KUKA iiwa14, Kinova Gen3 lite), checked on placements the
fit never saw, against the nominal model and, where the source publishes its own calibrated model with the
placement it was fitted on, against that model (MUKCa's optimiser).

    python benchmarks/realdata_sockets.py          # writes docs/benchmarks/realdata_sockets.md

Data: benchmarks/data/mukca2025 (scripts/convert_mukca2025.py; MIT). Each split runs what a user runs:
``identify_sockets`` on the fit placements (``rodlab calibrate --sockets --fit-placements``), then
``check_sockets`` of each model on the held-out placements: the spread of the ball positions about each
socket's centre (consistency) and the error of the 50 mm socket distance (distortion), both in mm.
"""
from __future__ import annotations

import argparse
import logging
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT / "benchmarks" / "data" / "mukca2025"
#: (robot data, URDF, fit placements, the source's own calibrated URDF fitted on the same placements or None)
SPLITS = [("panda_6", "panda.urdf", [1], "panda_6_mukca_calibrated.urdf"),
          ("panda_7", "panda.urdf", [1], "panda_7_mukca_calibrated.urdf"),
          ("panda_2", "panda.urdf", [1, 3, 5, 7, 9], None),
          ("panda_3", "panda.urdf", [1, 3, 5], None),
          ("kuka_14", "iiwa14.urdf", [1, 3], None),
          ("dinova_1", "gen3lite.urdf", [1, 3], None),
          ("dinova_2", "gen3lite.urdf", [1, 3], None)]


def _cell(c) -> str:
    return f"{c.spread_mm.mean():.3f} / {c.spread_max_mm:.3f} | {c.distance_rms_mm:.3f}"


def run_split(name: str, urdf: str, fit_on: list, theirs: str | None) -> list[str]:
    """One table row: the held-out checks of the nominal, rodlab's and (if any) the source's model."""
    from rodlab.calibrate import read_robot
    from rodlab.calibrate.plausible import constrain_to_ranges
    from rodlab.calibrate.socket_check import check_sockets
    from rodlab.calibrate.socket_fit import identify_sockets, socket_start
    from rodlab.calibrate.sockets import read_sockets
    robot = read_robot(DATA / urdf, tip_link="ball_link")
    readings = read_sockets(DATA / f"{name}.sockets.csv", robot.n)
    held = sorted(set(readings.placement.tolist()) - set(fit_on))
    test = readings.subset(held)
    t0 = time.perf_counter()
    fits = []                       # what the CLI runs: an insignificant excursion held at its range's end, refitted

    def fit_with(pins):
        fits.append(identify_sockets(robot, readings.subset(fit_on), pinned=pins, fix_unidentifiable=True))
        return fits[-1].result

    constrain_to_ranges(fit_with)
    fit = fits[-1]
    seconds = time.perf_counter() - t0
    nominal, calibrated = check_sockets(robot, socket_start(robot, test), test), check_sockets(robot, fit.result.params,
                                                                                                test)
    row = [name, ",".join(map(str, fit_on)), ",".join(map(str, held)), str(test.n), _cell(nominal), _cell(calibrated)]
    if theirs:
        other = read_robot(DATA / theirs, tip_link="ball_link")
        row.append(_cell(check_sockets(other, socket_start(other, test), test)))
    else:
        row.append("- | -")
    row += [f"{fit.result.rms_mm * 1e3:.0f}", f"{seconds:.2f}", _verdict(fit.result, nominal, calibrated)]
    return ["| " + " | ".join(row) + " |"]


def _verdict(res, nominal, calibrated) -> str:
    """What ``rodlab calibrate --sockets --fit-placements`` says: trusted (usable: the held-out placements' spread
    clearly below the nominal model's, plausible parameters) or not, with the completeness statement."""
    from rodlab.calibrate.crossval import Prediction
    from rodlab.calibrate.trust import completeness, prediction_warnings
    warnings = res.warnings + prediction_warnings(Prediction.of_validation(calibrated.spread_mm, nominal.spread_mm,
                                                                           res.rms_mm))
    complete = f"model {completeness(res)}, {res.residual_check.birge:.1f} x seat play"
    held = [u.split(" ")[0] for u in res.unidentifiable if "end of its physical range" in u]
    complete += f"; {', '.join(held)} held at the end of its range" if held else ""
    return ("trusted" if not warnings else "NOT TRUSTED (" + "; ".join(w.split(":")[0] for w in warnings[:2]) + ")") \
        + f"; {complete}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("-o", "--output", type=Path, default=ROOT / "docs" / "benchmarks" / "realdata_sockets.md")
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    if not (DATA / "panda.urdf").exists():
        print(f"skipped: {DATA} is missing (python scripts/convert_mukca2025.py SRC_DIR)")
        return 0
    lines = ["# Ball-in-socket calibration on real data (MUKCa)", "",
             "Checked on held-out placements: per model, the spread of the ball positions about their socket's "
             "centre, mean / max [mm], and the rms error of the 50 mm socket distance [mm]. Written by "
             "`python benchmarks/realdata_sockets.py`.", "",
             "| data | fit on | checked on | readings | nominal spread | nominal distance | rodlab spread | "
             "rodlab distance | MUKCa's own spread | MUKCa's own distance | fit rms um | fit s | verdict (exit 0 if trusted) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for split in SPLITS:
        lines += run_split(*split)
        print(lines[-1])
    sys.path.insert(0, str(Path(__file__).parent))
    from pages import write_page
    write_page(args.output, lines, Path(__file__).with_name("realdata_sockets_notes.md"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
