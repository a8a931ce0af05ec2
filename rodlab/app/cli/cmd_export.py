"""``rodlab export``: a calibration result in the forms controllers and ROS take (URDF, YAML, DH table CSV)."""
from __future__ import annotations

import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.calibrate import builtin_robots, read_points, robot_path
from rodlab.calibrate.kinematics import ModelParams
from rodlab.calibrate.result import calibrated_params, description_notes, read_calibration

from ...core.errors import RodlabError
from .argtypes import seed
from .robotargs import add_robot_options, robot_from_args

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("export", help="write a calibration as a corrected URDF, a YAML and a DH table",
                       description="A calibration result (rodlab calibrate --json) in the forms controllers and "
                                   "ROS take: with --urdf the robot's own URDF with its joint origins corrected "
                                   "(checked by reading the file back: <= 1 um), the measurement frame and the "
                                   "tool point as fixed joints; always a YAML of the calibrated parameters with "
                                   "1-sigma and joint compliances, and the DH table as CSV (nominal, calibrated, "
                                   "sigma).")
    p.add_argument("calibration", help="the calibration result (*.json from rodlab calibrate --json)")
    add_robot_options(p, default=None, help="the robot the calibration used (name or file); with --urdf the URDF "
                                           "itself is the robot")
    p.add_argument("--urdf", default=None, help="the robot's URDF: write it back with calibrated joint origins")
    p.add_argument("--validate", default=None,
                   help="validation points whose configurations check the written URDF (default: 200 random "
                        "configurations within the joint limits)")
    p.add_argument("--seed", type=seed, default=0, help="seed of the random check configurations")
    p.add_argument("-o", "--output", required=True,
                   help="OUT.urdf (the YAML and CSV beside it, same stem) or a folder")
    p.set_defaults(func=cmd_export)


def _outputs(args, robot) -> tuple[Path | None, Path, Path]:
    out = Path(args.output)
    if out.suffix.lower() == ".urdf":
        stem = out.with_suffix("")
    else:
        stem = out / f"{robot.name}_calibrated"
    return (stem.with_suffix(".urdf") if args.urdf else None, Path(f"{stem}.yaml"), Path(f"{stem}.dh.csv"))


def _check_configurations(args, robot) -> np.ndarray:
    if args.validate:
        return np.deg2rad(read_points(args.validate, robot.n).q_deg)
    lo, hi = robot.limits_deg[:, 0], robot.limits_deg[:, 1]
    return np.deg2rad(np.random.default_rng(args.seed).uniform(lo, hi, (200, robot.n)))


def _warn_outside_range(cal, q_rad) -> None:
    """The periodic joint errors hold over the readings they were identified on: say where the check left them."""
    for j, (lo, hi) in sorted(cal.harmonic_range_deg.items()):
        q = np.rad2deg(np.atleast_2d(q_rad)[:, j - 1])
        out = int(np.sum((q < lo - 1e-9) | (q > hi + 1e-9)))
        if out:
            print(f"note: joint {j}'s periodic error was identified over {lo:.1f}..{hi:.1f} deg; {out} of {len(q)} "
                  f"check configurations lie outside it, where it is an extrapolation (give --validate with "
                  f"configurations of the robot's work)", file=sys.stderr)


#: deviations from an analytic-IK assumption worth a warning: TCP effect [mm]
IK_WARN_MM = 0.001


def _warn_ik_assumptions(robot, params) -> None:
    """Where the calibrated geometry is no longer what a closed-form IK of the nominal arm assumes (parallel or
    intersecting axes), and by how much: such a controller cannot take these parameters; `rodlab correct` can."""
    from rodlab.calibrate.correct import ik_assumptions
    broken = [d for d in ik_assumptions(robot, params, ModelParams.nominal(robot, params.tool)) if d.effect_mm > IK_WARN_MM]
    for d in broken:
        print(f"warning: {d.describe()}", file=sys.stderr)
    if broken:
        print("note: a controller with the nominal arm's analytic IK cannot represent these deviations; keep its "
              "model and send it corrected targets or joint commands instead: `rodlab correct CAL.json "
              "TARGETS.csv -o COMMANDS.csv`", file=sys.stderr)


def _warn_rod_twist(robot, cal) -> None:
    """The last joint's zero offset, identified with a rod, carries the rod's mounting twist about the flange axis
    (calibrate.params: one rod cannot separate them): said, with what it does to a production tool."""
    p = cal.parameters.get(f"dtheta_{robot.n}")
    if p is None or p.status != "identified" or abs(p.value) < 0.01:
        return
    print(f"warning: dtheta_{robot.n} = {p.value:+.4f} deg (written as the joint's zero offset) is the robot's joint-"
          f"{robot.n} zero plus the rod's mounting twist about the flange axis, which one rod cannot separate; a "
          f"production tool turns with it ({np.deg2rad(abs(p.value)) * 200.0:.2f} mm per 200 mm off the flange axis): before "
          "a controller relies on it, measure the twist (the rod's pin against the flange, or a second clamping of "
          "the rod turned on the flange) or keep that offset at its nominal value", file=sys.stderr)


def _urdf_file(spec: str) -> str:
    """--urdf takes a URDF file or a built-in robot's name (ur5: its own URDF); a folder does not hide the name."""
    path = robot_path(spec)
    if path.suffix.lower() != ".urdf":
        urdfs = sorted(name for name, f in builtin_robots().items() if f.suffix == ".urdf")
        raise RodlabError(f"--urdf {spec}: {path.name} is not a URDF; give a URDF robot (built-in: "
                          f"{', '.join(urdfs)}) or export with --robot {spec} (the YAML and the DH table)")
    return str(path)


@dataclass(frozen=True)
class _LeftOut:
    """What the exported geometry (URDF joint origins, DH table) leaves out of the calibrated model: the joint
    compliance's and the periodic joint errors' largest TCP effect [mm] over the check configurations."""

    compliance_mm: float
    periodic_mm: float

    @property
    def text(self) -> str:
        parts = ([f"joint compliance (up to {self.compliance_mm:.3f} mm at the TCP there, no payload)"]
                 if self.compliance_mm > 0 else []) + \
            ([f"the periodic joint errors (up to {self.periodic_mm:.3f} mm)"] if self.periodic_mm > 0 else [])
        return f"{' and '.join(parts)} {'are' if len(parts) > 1 else 'is'}" if parts else ""


def _left_out(robot, params: ModelParams, q_check) -> _LeftOut:
    from rodlab.calibrate.export_urdf import omitted_mm
    c_mm, h_mm = omitted_mm(robot, params, q_check)
    return _LeftOut(c_mm if params.c.any() else 0.0, h_mm if params.h.any() else 0.0)


def _warn_geometry_alone(cal, left: _LeftOut, where: str) -> None:
    """A consumer of the exported geometry that does not add what it leaves out (ROS, most controllers) loses
    accuracy: a warning where that is more than the model's own error, a note where it is more than 0.02 mm."""
    rms = cal.residual_rms_mm
    for what, mm, fix in (("the joint compliance", left.compliance_mm, "with --kinematic-only"),
                          ("the periodic joint errors", left.periodic_mm, "without --joint-harmonics")):
        if mm <= 0.02:
            continue
        worse = mm > rms
        print(f"{'warning' if worse else 'note'}: a consumer of {where} that does not add {what} (ROS, most "
              f"controllers) gets up to {mm:.3f} mm more error than the calibrated model"
              + (f", more than the model's own error ({rms:.3f} mm rms)" if worse else "")
              + f": for such a consumer calibrate again {fix} (`rodlab calibrate ...`) and export that result",
              file=sys.stderr)


def cmd_export(args) -> int:
    from rodlab.calibrate.export_tables import write_dh_csv, write_params_yaml
    if args.urdf and args.robot:
        raise RodlabError("give --urdf (the URDF is the robot) or --robot, not both")
    cal = read_calibration(args.calibration)
    if args.urdf:
        args.urdf = _urdf_file(args.urdf)
    if not args.urdf and not args.robot:
        if cal.robot not in builtin_robots():
            raise RodlabError(f"name the robot the calibration used ({cal.robot!r} is not built in): --robot "
                              "NAME_OR_FILE, or --urdf ROBOT.urdf")
        args.robot = cal.robot
    args.robot = args.robot or args.urdf
    robot = robot_from_args(args)
    if not args.urdf and str(getattr(robot, "path", "") or "").lower().endswith(".urdf"):
        args.urdf = str(robot.path)                     # a URDF robot: its own file is written back calibrated
    params = calibrated_params(robot, cal)
    for line in description_notes(robot, cal):
        print(line, file=sys.stderr)
    urdf_out, yaml_out, csv_out = _outputs(args, robot)
    if urdf_out is None and Path(args.output).suffix.lower() == ".urdf":
        print(f"note: no URDF written: {robot.name} is a DH table, not a URDF (give --urdf ROBOT.urdf to write one "
              "calibrated); the YAML and the DH table carry the calibration", file=sys.stderr)
    q_check = _check_configurations(args, robot)
    left_out = _left_out(robot, params, q_check)
    origins = None
    if urdf_out is not None:
        from rodlab.calibrate.export_urdf import write_calibrated_urdf
        res = write_calibrated_urdf(args.urdf, robot, params, urdf_out, q_check,
                                    args.base_link, args.tip_link, source=Path(args.calibration).name)
        origins = res.origins
        note = f"; {left_out.text} not in the URDF, see the YAML" if left_out.text else ""
        print(f"wrote {res.path} (read back: TCP within {res.max_error_um:.2g} um of the calibrated model's geometry "
              f"over {res.configurations} configurations{note})")
        _warn_outside_range(cal, q_check)
        if args.tip_link:
            from rodlab.calibrate.export_urdf import TCP_LINK
            print(f"note: the calibrated tool point is the link {TCP_LINK!r} of {res.path.name}, not {args.tip_link!r} "
                  f"(kept as the robot had it): load it with --tip-link {TCP_LINK} to calibrate or validate with the "
                  "calibrated model", file=sys.stderr)
    _warn_geometry_alone(cal, left_out, "the URDF or the DH table" if urdf_out is not None else "the DH table")
    _warn_ik_assumptions(robot, params)
    _warn_rod_twist(robot, cal)
    print(f"wrote {write_params_yaml(yaml_out, robot, cal, params, origins)}")
    print(f"wrote {write_dh_csv(csv_out, robot, cal, params)}")
    if not cal.trusted:                 # written, as calibrate writes its result: exit 3 as calibrate's does
        print(f"warning: {Path(args.calibration).name} says trusted: false (NOT TRUSTED): read its warnings "
              "(fit.warnings) before loading these parameters into a controller", file=sys.stderr)
        return 3
    return 0
