"""``rodlab correct``: TCP targets to the joint commands (or the corrected nominal-model targets) that put the
calibrated robot on them (:mod:`rodlab.calibrate.correct`)."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from rodlab.calibrate import CalibrationError, builtin_robots
from rodlab.calibrate.kinematics import ModelParams
from rodlab.calibrate.result import calibrated_params, description_notes, read_calibration
from rodlab.core.frames import rotation_from_abc

from ...core.errors import RodlabError
from .robotargs import add_robot_options, robot_from_args

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("correct", help="TCP targets -> joint commands that put the calibrated robot on them",
                       description="For TCP position targets (x_mm, y_mm, z_mm in the calibration's measurement "
                                   "frame) or poses (also a_deg, b_deg, c_deg: the tool frame's orientation, R = "
                                   "Rx(a) Ry(b) Rz(c); solved by a 6-D IK), optional q1..qn [deg]: the program's "
                                   "configuration, where the IK starts, the joint commands that put the calibrated "
                                   "robot's TCP on each target, and the "
                                   "corrected targets to give a controller that keeps its nominal model and analytic "
                                   "IK, with the IK residual, how far the uncorrected program lands, and the "
                                   "calibration's predicted accuracy.")
    p.add_argument("calibration", help="the calibration result (*.json from rodlab calibrate --json)")
    p.add_argument("targets", help="*.targets.csv: x_mm,y_mm,z_mm[,a_deg,b_deg,c_deg][,q1..qn]")
    add_robot_options(p, default=None, help="the robot the calibration used (default: the one it names, if built in)")
    p.add_argument("--tool", default=None, metavar="X,Y,Z",
                   help="the TCP in the flange frame {n} [mm] (default: the calibrated tool point, the measured "
                        "target)")
    p.add_argument("--tool-abc", default=None, metavar="A,B,C",
                   help="pose targets: the tool frame's orientation in the flange frame {n} (contract A, B, C "
                        "[deg]; default: the flange's axes)")
    p.add_argument("--seed-q", default=None, metavar="Q1,...,QN",
                   help="the configuration [deg] the IK starts from for targets without q columns (default: every "
                        "joint at 20 deg)")
    p.add_argument("-o", "--output", required=True, help="COMMANDS.csv")
    p.set_defaults(func=cmd_correct)


def _vector(text: str | None, size: int, what: str) -> np.ndarray | None:
    if text is None:
        return None
    try:
        v = np.array([float(x) for x in text.split(",")])
    except ValueError:
        v = np.zeros(0)
    if v.size != size or not np.all(np.isfinite(v)):
        raise RodlabError(f"{what} {text!r}: expected {size} comma-separated numbers")
    return v


def _predicted_mm(path) -> float | None:
    """The calibration's held-out mean error [mm] (``fit.prediction``), if it recorded one."""
    pred = json.loads(Path(path).read_text(encoding="utf-8")).get("fit", {}).get("prediction") or {}
    return pred.get("mean_mm")


def _pinned_words(sd) -> str:
    """The per-target uncertainty's range in the summary line (param_sd_mm), or nothing without one."""
    if sd is None:
        return ""
    finite = sd[np.isfinite(sd)]
    if finite.size == 0:
        return "; a parameter the calibration could not see leaves the targets' uncertainty unbounded (param_sd_mm inf)"
    pinned = f"; its parameters pin the targets to {np.min(finite):.3f}-{np.max(finite):.3f} mm (1 sigma, param_sd_mm)"
    if np.isinf(sd).any():
        pinned += (f"; at {int(np.isinf(sd).sum())} of {sd.size} targets a parameter the calibration could not see moves "
                   "the TCP: unbounded (param_sd_mm inf)")
    return pinned


def cmd_correct(args) -> int:
    from rodlab.calibrate.correct import correct_targets
    from rodlab.calibrate.target_uncertainty import tcp_sd_mm
    from rodlab.calibrate.targets import commands_csv, read_targets
    cal = read_calibration(args.calibration)
    if not args.robot:
        if cal.robot not in builtin_robots():
            raise RodlabError(f"name the robot the calibration used ({cal.robot!r} is not built in): --robot "
                              "NAME_OR_FILE")
        args.robot = cal.robot
    robot = robot_from_args(args)
    params = calibrated_params(robot, cal)
    for line in description_notes(robot, cal):
        print(line, file=sys.stderr)
    tool = _vector(args.tool, 3, "--tool")
    if tool is not None:
        params = params.with_(tool=tool)
    nominal = ModelParams.nominal(robot, params.tool).with_(base=params.base)
    targets = read_targets(args.targets, robot.n)
    seed_deg = _vector(args.seed_q, robot.n, "--seed-q")
    seeds = targets.q_seed_deg if targets.q_seed_deg is not None else (
        seed_deg if seed_deg is not None else np.full(robot.n, 20.0))
    if targets.poses:
        corr = _correct_poses(args, robot, params, nominal, targets, np.deg2rad(seeds))
    elif args.tool_abc is not None:
        raise RodlabError(f"--tool-abc orients the tool frame of pose targets; {args.targets} has positions only "
                          "(add a_deg,b_deg,c_deg columns, or leave --tool-abc out)")
    else:
        corr = correct_targets(robot, params, nominal, targets.targets_mm, np.deg2rad(seeds))
    predicted = _predicted_mm(args.calibration)
    sd = tcp_sd_mm(robot, params, corr.q_rad, cal)
    path = commands_csv(args.output, targets, corr, predicted,
                        [f"rodlab correct {Path(args.calibration).name} {Path(args.targets).name} (robot {robot.name})",
                         "q1..qn: joint commands [deg] that put the calibrated robot's TCP on the target; corrected_*: "
                         "the target to give a controller with the nominal model",
                         "residual_um: IK residual; uncorrected_mm: where the nominal program's joints put the "
                         "calibrated TCP; predicted_mm: the calibration's held-out mean error; param_sd_mm: the TCP's "
                         "1-sigma uncertainty at the commands from the identified parameters (grows away from the "
                         "measured poses; empty for a result without fit.correlation)"]
                        + (["pose targets: a_deg..c_deg and corrected_a_deg..: the tool frame, R = Rx(a) Ry(b) Rz(c) "
                            "in {W}; residual_urad, uncorrected_mrad: the same for the orientation"]
                           if targets.poses else []), sd)
    print(f"wrote {path}: {len(corr.ok)} targets, IK residual max {corr.residual_mm.max() * 1e3:.3f} um"
          + (f" and {corr.residual_rad.max() * 1e6:.3f} urad" if targets.poses else "") + "; the "
          f"uncorrected program misses by {corr.uncorrected_mm.mean():.3f} mm mean ({corr.uncorrected_mm.max():.3f} "
          f"max)" + (f"; the calibration predicts {predicted:.3f} mm held-out mean error" if predicted else "")
          + _pinned_words(sd))
    if not corr.ok.all():
        bad = np.nonzero(~corr.ok)[0] + 1
        print(f"warning: {len(bad)} target(s) not reached within the joint limits (rows {bad[:10].tolist()}); their "
              f"ok column is 0: give their program configuration (q1..q{robot.n})", file=sys.stderr)
    if not cal.trusted:
        print(f"note: {Path(args.calibration).name} says trusted: false; read its warnings before using these "
              "commands", file=sys.stderr)
    return 0


def _correct_poses(args, robot, params, nominal, targets, seeds_rad):
    """Pose targets: the 6-D IK; a pose the calibrated robot cannot reach is refused with its line (no output)."""
    from rodlab.calibrate.correct import correct_poses
    abc = _vector(args.tool_abc, 3, "--tool-abc")
    R_tool = None if abc is None else rotation_from_abc(abc)
    corr = correct_poses(robot, params, nominal, targets.targets_mm, targets.abc_deg, seeds_rad, R_tool)
    if not corr.ok.all():
        k = int(np.nonzero(~corr.ok)[0][0])
        raise CalibrationError(
            f"target {k + 1} is not reachable as a pose by the calibrated robot within its joint limits (closest "
            f"{corr.residual_mm[k]:.3g} mm and {np.rad2deg(corr.residual_rad[k]):.3g} deg away"
            + (f"; {int((~corr.ok).sum())} target(s) in all" if (~corr.ok).sum() > 1 else "") + "): move it into the "
            f"workspace, away from a stretched or singular arm, or give its program configuration (q1..q{robot.n})",
            path=targets.path, line=int(targets.lines[k]) if targets.lines is not None else None)
    return corr
