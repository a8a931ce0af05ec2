"""``rodlab plan``: rod orientations per clamping position chosen by observability (O1)."""
from __future__ import annotations

import argparse
import sys

import numpy as np

from rodlab.calibrate import Rod, read_fixture
from rodlab.calibrate.result import read_calibration

from ...core.calc import calc_rod_compliance
from ...core.compliance import read_compliance
from ...core.design_io import load_design
from ...core.errors import RodlabError
from ...core.fileio import atomic_write_text
from .argtypes import base_pose, count, seed
from .robotargs import add_robot_options, robot_from_args
from .rodargs import design_of_compliance

__all__ = ["register", "cmd_plan"]


def register(sub) -> None:
    p = sub.add_parser("plan", help="choose rod orientations per clamping position by observability (O1)",
                       description="Reachable rod orientations at every clamping position (numeric IK within the "
                                   "joint limits), chosen to maximise the observability index O1; prints O1-O5 and "
                                   "writes the joint angles for the robot program.")
    add_robot_options(p)
    p.add_argument("--fixture", required=True, help="*.fixture.json (the clamping positions to plan at)")
    p.add_argument("--rod", required=True, help="a compliance file (tool, mass) or a *.rod.toml design")
    p.add_argument("-k", type=count, default=6, help="orientations per position (default 6)")
    p.add_argument("--candidates", type=count, default=24,
                   help="reachable candidate orientations drawn per position (default 24)")
    p.add_argument("--seed", type=seed, default=0, help="random seed of the candidates (default 0)")
    p.add_argument("--limit-margin-deg", type=margin, default=None, metavar="DEG",
                   help="keep every joint this far inside its limits (default 5: a pose on a hard limit is one a "
                        "controller stops short of; 0: the limits themselves)")
    p.add_argument("--floor-mm", type=finite, default=None, metavar="H",
                   help="keep every joint's origin (shoulder, elbow, wrist) above this height [mm] in the robot's base "
                        "frame {0}, measured up against gravity: the floor or table under the robot (default: no "
                        "floor; where {0} sits, at the floor or at the shoulder, depends on the robot file)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--base", type=base_pose, default=None, metavar="X,Y,Z,A,B,C",
                       help="where the robot stands: the pose of its base frame {0} in {W} [mm, deg], as a "
                            "calibration result's base_x..base_c; write --base=-1107,46,... when X is negative "
                            "(default: the standard layout, {W} 650 mm in front "
                            "of the robot and 250 mm up, with a warning)")
    where.add_argument("--calibration", default=None, metavar="CAL.json",
                       help="take the base pose from an earlier calibration result of this robot and layout")
    p.add_argument("-o", "--output", default=None, help="CSV of joint angles (position,point,q1..qn)")
    p.set_defaults(func=cmd_plan)


def cmd_plan(args) -> int:
    from rodlab.calibrate.plan import LIMIT_MARGIN_DEG, Reach, plan_poses
    robot = robot_from_args(args)
    fix = read_fixture(args.fixture)
    design = load_design(args.rod) if str(args.rod).endswith(".toml") else None
    rod = calc_rod_compliance(design) if design is not None else read_compliance(args.rod)
    base = _base(args)
    margin = LIMIT_MARGIN_DEG if args.limit_margin_deg is None else args.limit_margin_deg
    poses, obs = plan_poses(robot, fix, Rod.of(rod), args.k, args.candidates, args.seed, base_guess=base,
                            exit_n=_rod_exit(args, design, rod), reach=Reach(margin, args.floor_mm))
    print(f"{sum(len(v) for v in poses.values())} poses over {len(poses)} positions; observability: " +
          ", ".join(f"{k} {v:.4g}" for k, v in obs.items()))
    lines = ["position,point," + ",".join(f"q{i + 1}" for i in range(robot.n))]
    for j, qs in poses.items():
        for i, q in enumerate(qs, start=1):
            lines.append(f"{j},{i}," + ",".join(f"{v:.4f}" for v in q))
    if args.output:
        print(f"wrote {atomic_write_text(args.output, chr(10).join(lines) + chr(10))}")
    else:
        print("\n".join(lines))
    return 0


def margin(text: str) -> float:
    """``--limit-margin-deg``: a number of degrees >= 0."""
    v = finite(text)
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a margin of 0 deg or more, got {text!r}")
    return v


def finite(text: str) -> float:
    try:
        v = float(text)
    except ValueError:
        v = float("nan")
    if not np.isfinite(v):
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}")
    return v


BASE_KEYS = ("base_x", "base_y", "base_z", "base_a", "base_b", "base_c")


def _rod_exit(args, design, rod) -> np.ndarray:
    """The direction in {n} along which the rod leaves its ball (back along pipe II: its bend angle gamma decides
    it), from the design given, the design file the compliance file names, or the built-in design of its rod's
    name with the same tool vector; without one an L-shaped rod (gamma 90) is assumed, with a warning."""
    if design is None:
        design = design_of_compliance(rod)
        if design is not None and not np.allclose(design.tool_mm, rod.tool_mm, atol=1.0):
            design = None
    if design is None:
        print(f"warning: {args.rod}: the rod's bend angle is not known (no design file): it is taken to leave the "
              "ball along -x of the flange (an L-shaped rod, gamma 90 deg); give its *.rod.toml as --rod to plan "
              "with its own", file=sys.stderr)
        return np.array([-1.0, 0.0, 0.0])
    return -design.pipe_II_direction


def _base(args):
    """The base pose [mm, deg] from --base or --calibration; None (with a warning) for the standard layout."""
    if args.base is not None:
        return args.base
    if args.calibration:
        cal = read_calibration(args.calibration)
        missing = [k for k in BASE_KEYS if k not in cal.parameters]
        if missing:
            raise RodlabError(f"{args.calibration}: no {', '.join(missing)} in its parameters: give --base instead")
        return np.array([cal.parameters[k].value for k in BASE_KEYS])
    print("warning: the robot's base pose in {W} is not given (--base or --calibration): the standard layout is "
          "assumed ({W} 650 mm in front of the robot and 250 mm up, the device tilted as in the paper); the planned "
          "angles reach the datum points only if the robot stands so", file=sys.stderr)
    return None
