"""``rodlab calibrate``: identify a robot from a MultiCal campaign (or instrument points, or socket readings)."""
from __future__ import annotations

import argparse
import functools
import sys

import numpy as np

from rodlab.calibrate import (
    ModelParams,
    RodDeflection,
    campaign_observations,
    deflection_offsets,
    result_dict,
    validate,
)
from rodlab.calibrate.device import read_device
from rodlab.calibrate.points import cross_validate_points, identify_points, stated_noise_mm
from rodlab.calibrate.compensations import compensations_help
from rodlab.calibrate.crossval import Prediction, cross_validate_identify
from rodlab.calibrate.mixups import campaign_mixup
from rodlab.calibrate.trust import gross, rms_text
from rodlab.calibrate.validate import clearly_worse

from ...core.errors import RodlabError
from .argtypes import joint_list
from .calibrateargs import add_identify_options, pins_from_args
from .calibration_printers import (print_cautions, print_not_trusted, print_parameters, write_residuals,
                                   write_result_file)
from .calibrate_excess import campaign_diagnosis, pose_off, robots_own
from .calibration_run import CalibrationRun, run_calibration, stated_noise_reason
from .deviceargs import add_device_option, points_from_args, refuse_rod_slips
from .reporting import default_folder, png_folder, write_command_report
from .rodargs import compliance_arg
from .columnsargs import screen_joint_columns
from .robotargs import robot_from_args
from .verdict import accept_validated, judge, print_verdict
from .cmd_sockets import calibrate_sockets

__all__ = ["register", "cmd_calibrate"]


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="identify a robot from a MultiCal campaign (or instrument points)",
                       description="Levenberg-Marquardt identification of the robot's kinematic errors, Hayati beta, "
                                   "base, tool and joint compliances from a MultiCal campaign, with rod-deflection "
                                   "compensation from a compliance file (paper Eqs. 2-19); or from an external "
                                   "instrument's points (--points). Compensations: " + compensations_help() + ".")
    p.add_argument("campaign", nargs="?", help="*.campaign.csv (omit with --points)")
    p.add_argument("--fixture", help="*.fixture.json (clamping poses, contact force)")
    add_device_option(p)
    p.add_argument("--rod", help="the rod's *.compliance.json (tool, mass, COM, C_F, C_g), or a design (rod1 .. rod6, "
                                 "a *.rod.toml) for its closed-form (calc) compliance")
    p.add_argument("--compensation", choices=["none", "file"], default="file",
                   help="file: compensate with the rod file's matrices (its method: calc / fea / meas); none: no "
                        "rod-deflection compensation")
    p.add_argument("--thermal", default=None, metavar="DESIGN",
                   help="also compensate the rod's thermal growth: the tool vector grows by each member's axial CTE "
                        "(the materials table) times its span, per kelvin of the campaign's temp_C column; DESIGN is "
                        "the rod's *.rod.toml or a built-in name")
    p.add_argument("--t-ref-c", type=float, default=20.0,
                   help="temperature [degC] the rod's tool vector is stated at (default 20; with --thermal)")
    p.add_argument("--points", default=None, help="calibrate from instrument points (*.validation.csv format)")
    p.add_argument("--sockets", default=None,
                   help="calibrate from ball-in-socket or ball-bar readings (*.sockets.csv): no instrument, the "
                        "sockets' places fitted jointly across the artefact's placements")
    p.add_argument("--fit-placements", default=None, metavar="LIST",
                   help="with --sockets: fit on these placements (e.g. 1,3) and check the model on the file's "
                        "others (consistency and distortion on placements the fit never saw)")
    p.add_argument("--kinematic-only", action="store_true",
                   help="hold every joint compliance at 0: the geometry then carries the average gravity sag, the "
                        "best model for a consumer that cannot add joint compliance (a URDF for ROS, most "
                        "controllers)")
    p.add_argument("--joint-harmonics", type=joint_list, default=(), metavar="LIST",
                   help="also identify a periodic angle error of these joints (e.g. 1,4): first and second harmonic "
                        "of the joint reading, h1s_j h1c_j h2s_j h2c_j [deg] (gear or encoder eccentricity, as "
                        "`rodlab diagnose` names it); the result is then rodlab.calibration/2")
    p.add_argument("--json", default=None, help="write the contract's calibration result here")
    p.add_argument("--png", default=None, type=png_folder,
                   help="folder for figures: residuals per position; with --validate the validation error distribution")
    p.add_argument("--residuals", default=None, metavar="RESIDUALS.csv",
                   help="write each point's residual (measured minus model in {W} [mm], with its joint angles and, for "
                        "a campaign, its position.point label) as a CSV")
    add_identify_options(p)
    p.set_defaults(func=cmd_calibrate)


def _refuse_mismatched_options(args) -> None:
    """Options the kind of data given does not use, refused with what to leave out."""
    if args.points and args.thermal:
        raise RodlabError("--thermal compensates a rod's growth during a campaign (its temp_C column); instrument "
                          "points (--points) have no rod to grow: leave --thermal out")
    if (args.points or args.sockets) and args.device:
        raise RodlabError("--device converts a campaign's raw sensor readings; instrument points and socket readings "
                          "have none: leave --device out")
    if args.sockets and args.residuals:
        raise RodlabError("--residuals writes the residual vectors of a campaign or instrument points; a socket fit's "
                          "residuals are distances: leave --residuals out (--json has the fit's rms)")
    if args.sockets and args.joint_harmonics:
        raise RodlabError("--joint-harmonics is for a campaign or instrument points; the socket fit (--sockets) has "
                          "no periodic joint errors: leave it out")


def cmd_calibrate(args: argparse.Namespace) -> int:
    _refuse_mismatched_options(args)
    if args.robot is None:
        if args.points or args.sockets:
            raise RodlabError(f"{'--points' if args.points else '--sockets'}: name the robot that made these readings "
                              "with --robot (a built-in name such as ur5, a robot TOML or a URDF); the tx90 default "
                              "is only for MultiCal campaigns")
        args.robot = "tx90"
        print("note: robot tx90 (the default, the paper's robot): give --robot NAME_OR_FILE for another",
              file=sys.stderr)
    if args.sockets:
        return calibrate_sockets(args)
    if args.points:
        return _calibrate_points(args)
    if not (args.campaign and args.fixture and args.rod):
        raise RodlabError("a campaign needs --fixture and --rod (or use --points for instrument data)")
    rod = compliance_arg(args.rod, slips_refused=True)
    refuse_rod_slips(rod, args.rod, args)
    comp = RodDeflection.of(None if args.compensation == "none" else rod)
    run = run_calibration(args, rod, comp)
    label = run.label
    robot, camp, res, before, after = run.robot, run.campaign, run.result, run.before, run.after
    _print_result(res, before, after, label)
    other_rod_mm = _warn_other_rod(res.params.tool, rod, args.rod)
    judge(res, _campaign_prediction(run))
    res.cautions = list(res.cautions) + _validation_misfit(run, args)
    res.warnings += _harmonics_held_out(run, args.joint_harmonics)
    noisy = stated_noise_reason(run, args)
    if noisy is not None:
        res.warnings.append(noisy)
    mixup = _mixup(run, suspect=noisy is not None) if res.warnings else None
    if mixup is not None and not args.columns_checked:       # files that do not describe the campaign: refused
        raise RodlabError(f"{args.campaign} with {args.fixture}: {mixup.reason()}; nothing was written (if the "
                          "files are right as they are, give --columns-checked)")
    if mixup is not None:                          # the cause first: the other reasons follow from it
        res.warnings.insert(0, mixup.reason())
    diagnosis = functools.cache(lambda: campaign_diagnosis(run, args, comp))     # run once, where needed
    # the robot's own errors, which the validation shows it works through, and no clamping pose recorded off
    accepted = mixup is None and accept_validated(res, lambda: robots_own(diagnosis()) and not pose_off(run))
    print_verdict(res)
    written = write_result_file(args, result_dict(robot, res, label, before, after))
    if args.residuals:
        written.append(write_residuals(args.residuals, res, camp.q_deg, camp.labels()))
    if args.png:
        from rodlab.calibrate.plots import plot_error_distributions, plot_residuals
        written.append(plot_residuals(res, camp, args.png))
        print(f"wrote {written[-1]}")
        if args.validate:
            errors = {"nominal": run.nominal_mm, f"calibrated ({label})": run.calibrated_mm}
            written.append(plot_error_distributions(errors, args.png))
            print(f"wrote {written[-1]}")
    write_command_report(args, written, default_folder(args))
    _note_uncompensated(robot, res, camp, run.fixture, args, rod, comp)
    if res.warnings:
        print_not_trusted(res)
        if mixup is None and res.residual_check is not None and res.residual_check.material:
            _print_suspects(diagnosis(), args, other_rod_mm)
        _note_ideal_device(args)
        return 3
    print_cautions(res)
    if accepted:
        _print_suspects(diagnosis(), args, other_rod_mm, heading="what the model leaves out")
    return 0


def _campaign_prediction(run: CalibrationRun):
    """The held-out accuracy: the validation points when given, else cross-validation over clamping positions; None
    where the fit itself is gross (:func:`~rodlab.calibrate.trust.gross`: files that do not fit together, refused
    whatever five more identifications of them would predict; a campaign of another robot's file: ~10 s saved)."""
    if run.calibrated_mm is not None:
        return Prediction.of_validation(run.calibrated_mm, run.nominal_mm, run.result.rms_mm)
    test = run.result.residual_check
    if run.result.warnings and test is not None and gross(test.birge, run.result.rms_mm):     # refused already
        print(f"note: no cross-validation: the fit itself leaves {run.result.rms_mm:.3g} mm rms ({test.birge:.0f} times "
              "the stated scatter), which no held-out error would make usable", file=sys.stderr)
        return None
    return cross_validate_identify(run.robot, run.observations, run.rod, run.compensations, run.options,
                                   fit_rms_mm=run.result.rms_mm)


def _note_ideal_device(args) -> None:
    """A not-trusted raw campaign read with exactly orthogonal sensors: say that a real device's are not."""
    if not getattr(args, "device", None):
        return
    dev = read_device(args.device)
    if np.max(np.abs(dev.misalignment_deg())) < 1e-6:
        print(f"  - {args.device} states exactly orthogonal sensors (a design, not a device as built): a real "
              f"device's axes are off by up to a degree or two, which puts several um on readings a few tenths of "
              f"a mm from the datum; give the device's calibrated axes", file=sys.stderr)


def _note_uncompensated(robot, res, camp, fix, args, rod, comp) -> None:
    """With ``--compensation none`` and a file that has matrices: how far the uncompensated rod deflects."""
    if comp.active or not (rod.C_F.any() or rod.C_g.any()):
        return
    obs = campaign_observations(camp, fix, rod)
    off = deflection_offsets(robot, res.params, obs.q_rad, obs.force_W_N, rod)
    print(f"note: the rod's deflection is not compensated; by {args.rod} it moves the ball up to "
          f"{np.linalg.norm(off, axis=1).max() * 1e3:.0f} um in this campaign (--compensation file compensates it)")


#: how far [mm] the identified tool may lie from the rod file's before the file is suspected of being another rod's
TOOL_MISMATCH_MM = 10.0


def _warn_other_rod(tool_mm, rod, path) -> float | None:
    """Warn when the identified ball centre is far from the rod file's tool vector (compared about the flange axis,
    which the identified flange twist turns the tool about): its compliance, mass and centre of mass would then
    be another rod's, and the compensation wrong."""
    t, f = np.asarray(tool_mm, float), np.asarray(rod.tool_mm, float)
    off = float(np.hypot(np.hypot(*t[:2]) - np.hypot(*f[:2]), t[2] - f[2]))
    if off > TOOL_MISMATCH_MM:
        print(f"warning: the identified ball centre (radius {np.hypot(*t[:2]):.1f} mm, z {t[2]:.1f} mm from the "
              f"flange) is {off:.0f} mm from the rod file's ({np.hypot(*f[:2]):.1f}, {f[2]:.1f} mm; {path}): is the "
              f"rod file this rod's? Its compliance, mass and centre of mass compensate the readings",
              file=sys.stderr)
        return off
    return None


def _mixup(run: CalibrationRun, suspect: bool = False):
    """A joint whose readings run the other way than the robot file's, or two clamping positions swapped, when the
    campaign is refused (:func:`~rodlab.calibrate.mixups.campaign_mixup`; ``suspect``: whatever its residual test
    says), or None."""
    return campaign_mixup(run.robot, run.result, run.campaign, run.fixture, run.rod_file, run.observations, run.rod,
                          run.compensations, run.options, suspect=suspect)


#: validation points missed by more than this many times their instrument's noise per coordinate show physics
#: the model leaves out (a clean calibration's: ~1-1.5x, the base and tool refitted on them)
VALIDATION_MISFIT = 2.5


def _validation_misfit(run: CalibrationRun, args) -> list[str]:
    """A caution where the validation points are missed by more than :data:`VALIDATION_MISFIT` times their
    instrument's noise per coordinate: physics outside the model shows there even where the campaign's own residuals
    are noise (a device trial: a periodic joint-4 error of 0.008 deg, 'complete? yes', validated 72 um rms per
    coordinate against a 20 um tracker; the campaign diagnosis with the validation points found it)."""
    if run.calibrated_mm is None or run.validation_noise_mm is None or run.calibrated_mm.size < 10:
        return []
    per_coord = float(np.sqrt(np.mean(run.calibrated_mm ** 2) / 3.0))
    ratio = per_coord / max(run.validation_noise_mm, 1e-9)
    if ratio < VALIDATION_MISFIT:
        return []
    return [f"the validation points are missed by {per_coord * 1e3:.0f} um rms per coordinate, {ratio:.1f} x their "
            f"instrument's noise ({run.validation_noise_mm * 1e3:.0f} um; give the points' sigma columns or "
            "--noise-um of their instrument if it is larger): the model leaves out physics that shows over the "
            "validation poses (a periodic joint error, a bending link), whatever the campaign's own residuals say; "
            f"`rodlab diagnose --campaign {args.campaign} --fixture {args.fixture} --rod {args.rod} --validate "
            f"{args.validate}` looks for it"]


def _harmonics_held_out(run: CalibrationRun, joints) -> list[str]:
    """A reason not to use the result when the periodic terms of ``--joint-harmonics`` make the validation points
    clearly worse than the same calibration without them (:func:`~rodlab.calibrate.validate.clearly_worse`): an
    IRB 4600 trial's bending forearm fitted as joint 3's harmonics doubled the held-out error."""
    if run.without_harmonics_mm is None or not clearly_worse(run.calibrated_mm, run.without_harmonics_mm):
        return []
    names = ", ".join(str(j) for j in joints)
    return [f"the periodic terms of joint(s) {names} (--joint-harmonics) predict the validation points worse: mean "
            f"{run.calibrated_mm.mean():.3f} mm with them, {run.without_harmonics_mm.mean():.3f} mm without; they fit "
            "the campaign's poses, not the robot (over less than a turn of the joint any smooth error fits them): "
            "calibrate without --joint-harmonics"]


def _uncompensated_todo(f) -> str:
    """What to do about the rod's deflection found in the residuals of a calibration told not to compensate it
    (a trial: "0.208x ... what the compliance file says (a file of another rod ...)" beside a right file, the
    factors being of a generic steel rod's deflection, what the identification had not already absorbed)."""
    k = f.parameters
    factors = (f" (the part the identified joint compliances and lengths did not absorb: {k['k_gravity']:.2f} of a "
               f"generic steel rod's deflection under its weight and {k['k_force']:.2f} of it under the contact "
               "force, not this rod's own factors)" if {"k_gravity", "k_force"} <= set(k) else "")
    return ("the rod deflects and this calibration does not compensate it (--compensation none): the residuals "
            f"still follow a rod's deflection{factors}; compensate the deflection through the rod's compliance file "
            "(`--rod FILE` with the default `--compensation file`, or `rodlab compare` for every method)")


def _print_suspects(diagnosis, args, other_rod_mm: float | None = None, heading: str = "suspects") -> None:
    """The campaign diagnosis (:func:`.calibrate_excess.campaign_diagnosis`: the same residual test, then the hypotheses, each
    checked on the validation points when there are some) and what to do about each; ``other_rod_mm``: how far the
    identified ball centre is from the rod file's (:func:`_warn_other_rod`), when the file looks like another rod's:
    a compliance found off is then that file's, not this rod's to measure."""
    from rodlab.app.diagnose.advice import remedy
    from rodlab.app.diagnose.campaign_holdout import HELD_OUT_WORSE
    diag, why = diagnosis
    if diag is None:           # the diagnosis identifies every parameter; the calibration held some at nominal
        print(f"suspects: the campaign diagnosis, which identifies every parameter, cannot run on this campaign "
              f"({why}); the verdict above stands", file=sys.stderr)
        return
    print(f"{heading} (`rodlab diagnose --campaign`, verdict {diag.verdict}):", file=sys.stderr)
    if not diag.findings:
        print("  (nothing it can name: the excess has no structure its effects or a position show)", file=sys.stderr)
    for f in diag.findings:
        where = f" at {f.location}" if f.location else ""
        if f.effect == "unexplained" and f.parameters.get("spread") == "even":
            where = f" (spread evenly over the positions and the campaign's time; least evenly at {f.location})"
        held = " (caution: " + f.evidence["caution"] + ")" if f.evidence.get(HELD_OUT_WORSE) else ""
        todo = remedy(f)
        if args.compensation == "none" and f.effect == "rod_deflection":
            todo = _uncompensated_todo(f)
        elif f.effect == "outliers" and args.robust:
            todo = (f"re-measure points {f.location.partition(':')[2]} (a gross alignment error); --robust already "
                    "down-weights them in this calibration")
        elif other_rod_mm is not None and f.effect == "rod_deflection":
            todo = (f"the rod file looks like another rod's (its ball {other_rod_mm:.0f} mm from the identified one, "
                    f"warned above): calibrate with this rod's compliance file first; {todo}")
        print(f"  - {f.effect}{where}: {todo}{held}", file=sys.stderr)


def _print_result(res, before, after, label) -> None:
    print(f"identification ({label} compensation): {len(res.free)} parameters from {res.residuals_mm.shape[0]} "
          f"points, residual rms {rms_text(res.rms_mm, 2)} per reading, {res.iterations} compensation passes, "
          f"{res.message}")
    print_parameters(res)
    if before is not None:
        print("  validation (base and tool refitted)   mean     max  median      SD  [mm]")
        for name, st in (("before (nominal)", before), ("after", after)):
            print(f"    {name:<34} {st.mean_mm:6.3f} {st.max_mm:7.3f} {st.median_mm:7.3f} {st.sd_mm:7.3f}")


def _shared_share(q_fit: np.ndarray, q_test: np.ndarray, tol_deg: float = 1e-3) -> float:
    """The share of the configurations ``q_test`` (m, n) [deg] that are one of ``q_fit`` (k, n) within ``tol_deg``
    on every joint."""
    fit = {tuple(row) for row in np.round(np.asarray(q_fit, float) / tol_deg).astype(np.int64)}
    test = np.round(np.asarray(q_test, float) / tol_deg).astype(np.int64)
    return float(np.mean([tuple(row) in fit for row in test])) if len(test) else 0.0


def _calibrate_points(args) -> int:
    robot = robot_from_args(args)
    pts, noise_mm = stated_noise_mm(points_from_args(args, args.points, robot), args.noise_um * 1e-3 if args.noise_um else None)
    options = dict(pinned=pins_from_args(args, robot.n), freed=args.free, robust=args.robust, harmonics=args.joint_harmonics)
    test = points_from_args(args, args.validate, robot) if args.validate else None
    for path, points in ((args.points, pts), (args.validate, test)):       # before minutes of a hopeless fit
        if points is not None:
            screen_joint_columns(args, robot, points, path, noise_mm)
    from rodlab.calibrate.plausible import constrain_to_ranges
    res, options["pinned"] = constrain_to_ranges(
        lambda pins: identify_points(robot, pts, noise_mm, fix_unidentifiable=not args.strict,
                                     **(options | {"pinned": pins})), options["pinned"], options["freed"])
    before = after = None
    errors = {}
    if test is not None:
        before, errors["nominal"], _ = validate(robot, ModelParams.nominal(robot, test.tool_mm), test)
        after, errors["calibrated"], _ = validate(robot, res.params, test)
        shared = _shared_share(pts.q_deg, test.q_deg)
        if shared >= 0.5:
            print(f"warning: --validate {args.validate}: {shared:.0%} of its joint "
                  f"configurations are the fit's own ({args.points}): its errors are no held-out test (they show the "
                  "fit, or only the other target); the verdict is judged by cross-validation instead. Validate on "
                  "configurations the fit has not seen", file=sys.stderr)
            errors = {}
    _print_result(res, before, after, "instrument points")
    judge(res, Prediction.of_validation(errors["calibrated"], errors["nominal"], res.rms_mm) if errors
          else cross_validate_points(robot, pts, res.rms_mm, **options))
    print_verdict(res)
    written = write_result_file(args, result_dict(robot, res, "none", before, after))
    if args.residuals:
        written.append(write_residuals(args.residuals, res, pts.q_deg, pts.names))
    if args.png:
        if not errors:
            print("note: --png draws the validation error distributions of instrument points; give --validate",
                  file=sys.stderr)
        else:
            from rodlab.calibrate.plots import plot_error_distributions
            written.append(plot_error_distributions(errors, args.png))
            print(f"wrote {written[-1]}")
    write_command_report(args, written, default_folder(args))
    if res.warnings:
        print_not_trusted(res)
    else:
        print_cautions(res)
    if res.residual_check is not None and res.residual_check.material:
        from ..diagnose.points import diagnose_points
        print("what the model leaves out, as `rodlab diagnose --points` sees it:", file=sys.stderr)
        print("\n".join("  " + line for line in diagnose_points(robot, pts, res, noise_mm).summary().splitlines()),
              file=sys.stderr)
    return 3 if res.warnings else 0
