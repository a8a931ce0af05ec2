"""``rodlab calibrate --sockets``: identify a robot from ball-in-socket or ball-bar readings (no instrument)."""
from __future__ import annotations

import math
import sys
from dataclasses import dataclass, replace

import numpy as np

from rodlab.calibrate import CalibrationError, result_dict
from rodlab.calibrate.socket_check import check_sockets
from rodlab.calibrate.socket_fit import identify_sockets, socket_start
from rodlab.calibrate.sockets import read_sockets
from rodlab.calibrate.crossval import Prediction

from ...core.enums import AccuracySource
from ...core.errors import RodlabError
from .calibrateargs import parse_pins
from .calibration_printers import print_cautions, print_not_trusted, print_parameters, write_result_file
from .reporting import default_folder, write_command_report
from .columnsargs import screen_joint_columns
from .robotargs import robot_from_args
from .verdict import judge, print_verdict

__all__ = ["calibrate_sockets", "SocketRun"]


@dataclass(frozen=True)
class SocketRun:
    """One socket calibration: the robot, the readings fitted and checked, the fit, and the checks.

    checks : {label: {"nominal": SocketCheck, "calibrated": SocketCheck}} for the fitted readings ("fit")
    and, when there are any, the readings the fit never saw ("held out")
    """

    robot: object
    fitted: object
    held_out: object | None
    fit: object
    checks: dict
    pins: dict                      # the fit's pins: the user's and the range holds (calibrate.plausible)


def _placements(text: str | None, readings) -> list[int]:
    """``--fit-placements 1,3``: placements the file has; all of them without the option."""
    have = sorted(set(readings.placement.tolist()))
    if text is None:
        return have
    try:
        chosen = sorted({int(t) for t in text.split(",") if t.strip()})
    except ValueError:
        raise RodlabError(f"--fit-placements {text!r}: expected placement numbers separated by commas, e.g. 1,3") \
            from None
    missing = [j for j in chosen if j not in have]
    if missing or not chosen:
        raise RodlabError(f"--fit-placements {text!r}: {readings.path} has placements {have}; "
                          f"{'not ' + str(missing) if missing else 'choose at least one'}")
    return chosen


def _readings(args, robot):
    """The fitted readings, the held-out ones (the file's other placements, or a --validate sockets file)."""
    readings = read_sockets(args.sockets, robot.n)
    if args.noise_um:
        key = "length_sigma_mm" if readings.ball_bar else "seat_sigma_mm"
        readings = replace(readings, **{key: args.noise_um * 1e-3})
    screen_joint_columns(args, robot, readings, args.sockets)       # the whole file, whichever placements are fitted
    chosen = _placements(args.fit_placements, readings)
    rest = sorted(set(readings.placement.tolist()) - set(chosen))
    held = readings.subset(rest) if rest else None
    if args.validate:
        if held is not None:
            raise RodlabError("--validate and --fit-placements both name readings to check on; use one")
        if not str(args.validate).endswith(".sockets.csv"):
            raise RodlabError(f"--validate {args.validate}: with --sockets the check is on other socket readings "
                              f"(a *.sockets.csv); instrument points check a --points calibration")
        held = read_sockets(args.validate, robot.n)
        screen_joint_columns(args, robot, held, args.validate)
    return readings.subset(chosen), held


def run_sockets(args) -> SocketRun:
    """Read, fit, and check the nominal and the calibrated model on the fitted and the held-out readings."""
    if args.thermal or args.points or args.campaign:
        raise RodlabError("--sockets is a calibration of its own: leave out the campaign, --points and --thermal")
    robot = robot_from_args(args)
    fitted, held = _readings(args, robot)
    from rodlab.calibrate.plausible import constrain_to_ranges
    fits = []

    def fit_with(pins):
        fits.append(identify_sockets(robot, fitted, pinned=pins, freed=args.free, fix_unidentifiable=not args.strict,
                                     robust=args.robust))
        return fits[-1].result

    _, pins = constrain_to_ranges(fit_with, parse_pins(args.pin), args.free)
    fit = fits[-1]
    checks = {}
    for label, r in (("fit", fitted), ("held out", held)):
        if r is not None:
            checks[label] = {"nominal": check_sockets(robot, socket_start(robot, r), r),
                             "calibrated": check_sockets(robot, fit.result.params, r)}
    return SocketRun(robot, fitted, held, fit, checks, pins)


def _print(run: SocketRun) -> None:
    r, res = run.fitted, run.fit.result
    kind = "ball-bar" if r.ball_bar else "ball-in-socket"
    print(f"identification ({kind} readings): {len(res.free)} parameters and {len(run.fit.centres_mm)} "
          f"{'pivot' if r.ball_bar else 'socket'} centres from {r.n} readings at {len(set(r.placement.tolist()))} "
          f"placement(s), {len(r.distances)} known distance(s); residual rms {res.rms_mm * 1e3:.1f} um per "
          f"{'length' if r.ball_bar else 'coordinate'}, {res.message}")
    print_parameters(res)
    with_distance = bool(r.distances)
    print("  consistency (ball spread about its socket)" + (" and distortion (socket distance error)"
                                                             if with_distance else "") + " [mm]")
    print(f"    {'readings':<10} {'model':<11} {'spread mean':>11} {'rms':>7} {'max':>7}"
          + (f"   {'distance rms':>12} {'max':>7}" if with_distance else ""))
    for label, pair in run.checks.items():
        for model, c in pair.items():
            print(f"    {label:<10} {model:<11} {c.spread_mm.mean():11.3f} {c.spread_rms_mm:7.3f} {c.spread_max_mm:7.3f}"
                  + (f"   {_num(c.distance_rms_mm, 12)} {_num(c.distance_max_mm, 7)}" if with_distance else ""))


def _num(v: float, width: int) -> str:
    """A table cell [mm]; ``-`` where these readings have no known distance."""
    return f"{v:{width}.3f}" if math.isfinite(v) else f"{'-':>{width}}"


def _extra(args, run: SocketRun) -> dict:
    """The result file's ``sockets`` record: the file, placements, centres, and the checks."""
    fit = run.fit
    return {"sockets": {
        "file": str(args.sockets), "ball_bar": run.fitted.ball_bar,
        "fit_placements": sorted(set(run.fitted.placement.tolist())),
        "centres_mm": {f"{p}.{s}": c.tolist() for (p, s), c in fit.centres_mm.items()},
        "centre_sigma_mm": {f"{p}.{s}": c.tolist() for (p, s), c in fit.centre_sigma_mm.items()},
        "distance_residuals_mm": fit.distance_residuals_mm.tolist(),
        "checks": {label: {m: c.to_dict() for m, c in pair.items()} for label, pair in run.checks.items()}}}


def _prediction(args, run: SocketRun):
    """The held-out accuracy: the spread of the held-out placements' (or file's) balls about their sockets,
    calibrated against nominal; without them, cross-validation leaving out one fitted placement at a time."""
    res = run.fit.result
    if "held out" in run.checks:
        pair = run.checks["held out"]
        return Prediction.of_validation(pair["calibrated"].spread_mm, pair["nominal"].spread_mm, res.rms_mm,
                                        "held-out placements (spread about their sockets)")
    placements = sorted(set(run.fitted.placement.tolist()))
    if len(placements) < 2:
        return None
    cal, nom, failed = [], [], []
    for p in placements:
        rest, test = run.fitted.subset([q for q in placements if q != p]), run.fitted.subset([p])
        try:
            fit = identify_sockets(run.robot, rest, pinned=run.pins, freed=args.free,
                                   fix_unidentifiable=True, robust=args.robust)
        except CalibrationError as e:
            failed.append(f"placement {p}: {e}")
            continue
        cal.append(check_sockets(run.robot, fit.result.params, test).spread_mm)
        nom.append(check_sockets(run.robot, socket_start(run.robot, test), test).spread_mm)
    return Prediction(AccuracySource.CROSS_VALIDATION, _joined(cal), _joined(nom), res.rms_mm,
                      "placements (spread about their sockets)", len(placements) - len(failed), failed)


def _joined(parts: list) -> np.ndarray:
    return np.concatenate(parts) if parts else np.zeros(0)


def calibrate_sockets(args) -> int:
    """The command: fit, print, write the result (``--json``, ``--report``), exit 3 when not trusted."""
    run = run_sockets(args)
    _print(run)
    res = run.fit.result
    judge(res, _prediction(args, run))
    print_verdict(res)
    written = write_result_file(args, result_dict(run.robot, res, "none", extra=_extra(args, run)))
    write_command_report(args, written, default_folder(args))
    if res.warnings:
        print_not_trusted(res)
        return 3
    print_cautions(res)
    if "held out" not in run.checks:
        print("note: every placement was fitted; --fit-placements checks the model on placements the fit never saw",
              file=sys.stderr)
    return 0
