"""``rodlab calibrate`` and ``rodlab compare``: identify a robot from a MultiCal campaign (or instrument points)."""
from __future__ import annotations

import argparse
import logging
import math
import sys
from pathlib import Path
from dataclasses import dataclass

import numpy as np

from ...compliance import RodCompliance, read_compliance
from ...errors import RodlabError
from ...units import DEVICE_NOISE_MM, TRACKER_NOISE_MM
from .argtypes import count, joint_list, nonneg_float, pos_float, seed
from .deviceargs import add_device_option, campaign_from_args, warn_flagged_fixture
from .reporting import add_report_option, default_folder, png_folder, write_command_report
from .robotargs import ROBOT_HELP, add_robot_options, robot_from_args
from .verdict import judge, print_held, print_verdict

__all__ = ["register", "run_calibration", "CalibrationRun", "print_parameters", "parse_pins", "print_not_trusted",
           "print_cautions", "write_result_file"]

log = logging.getLogger(__name__)



def _common(p) -> None:
    add_robot_options(p, default=None, help=ROBOT_HELP + "; default tx90 (the paper's robot) for a campaign, while "
                                                         "instrument points and socket readings must name theirs")
    p.add_argument("--validate", default=None,
                   help="validation points (*.validation.csv) for the paper's statistics; with --sockets, other "
                        "socket readings (*.sockets.csv) to check the model's consistency and distortion on")
    p.add_argument("--pin", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a parameter at a value (contract units), e.g. c_6=0 (repeatable)")
    p.add_argument("--free", action="append", default=[], metavar="NAME",
                   help="free a parameter the defaults hold, e.g. fixture_2_x (repeatable)")
    p.add_argument("--robust", action="store_true", help="soft-L1 loss (gross alignment errors lose weight)")
    p.add_argument("--noise-um", type=pos_float, default=None,
                   help="the measuring instrument's noise per coordinate [um], 1 sigma, that the trust verdict "
                        f"judges the residuals against (default: {DEVICE_NOISE_MM * 1e3:g} um for a MultiCal "
                        f"campaign; for --points the file's sigma_*_mm columns, else {TRACKER_NOISE_MM * 1e3:g} um: a laser "
                        f"tracker at a few metres; for --sockets the file's seat_sigma_mm / length_sigma_mm). Given, "
                        f"it replaces the per-point columns or the file's sigma")
    add_report_option(p)
    p.add_argument("--strict", action="store_true",
                   help="refuse a data set that cannot identify every parameter (naming them and the remedy) "
                        "instead of holding those at nominal")
    p.add_argument("--fix-unidentifiable", action="store_true",
                   help="hold the parameters these data cannot identify at nominal (and report them); the default "
                        "unless --strict, kept for scripts")


def register(sub) -> None:
    p = sub.add_parser("calibrate", help="identify a robot from a MultiCal campaign (or instrument points)",
                       description="Levenberg-Marquardt identification of the robot's kinematic errors, Hayati beta, "
                                   "base, tool and joint compliances from a MultiCal campaign, with rod-deflection "
                                   "compensation from a compliance file (paper Eqs. 2-19); or from an external "
                                   "instrument's points (--points).")
    p.add_argument("campaign", nargs="?", help="*.campaign.csv (omit with --points)")
    p.add_argument("--fixture", help="*.fixture.json (clamping poses, contact force)")
    add_device_option(p)
    p.add_argument("--rod", help="the rod's *.compliance.json (tool, mass, COM, C_F, C_g)")
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
    _common(p)
    p.set_defaults(func=cmd_calibrate)

    p = sub.add_parser("compare", help="run every compensation method on one campaign (the paper's Table 3)",
                       description="Calibrate one campaign with several compliance files (and none) and print the "
                                   "validation statistics in the layout of the paper's Table 3.")
    p.add_argument("campaign")
    p.add_argument("--fixture", required=True)
    add_device_option(p)
    p.add_argument("--rod", action="append", required=True, metavar="LABEL=FILE",
                   help="a compliance file per method, e.g. calc=rod1.calc.json fea=rod1.fea.json (repeatable)")
    p.add_argument("--png", default=None, help="the error distributions per method (the paper's Fig. 10): FILE.png, "
                                               "or a folder (it gets error_distributions.png)")
    p.add_argument("--json", default=None, help="write the table (format rodlab.comparison/1, docs/formats.md)")
    _common(p)
    p.set_defaults(func=cmd_compare)
    register_more(sub)


def _pins(args, n: int) -> dict:
    """``--pin`` values, and with ``--kinematic-only`` every joint compliance at 0."""
    pins = parse_pins(args.pin)
    if getattr(args, "kinematic_only", False):
        pins.update({f"c_{i}": 0.0 for i in range(2, n + 1)})
    return pins


def parse_pins(items) -> dict:
    out = {}
    for it in items:
        k, eq, v = it.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise RodlabError(f"--pin {it!r}: expected NAME=VALUE") from None
        if not eq:
            raise RodlabError(f"--pin {it!r}: expected NAME=VALUE")
    return out


@dataclass
class CalibrationRun:
    """One campaign identified and, with ``--validate``, checked on the validation points.

    Attributes
    ----------
    robot, campaign : what was read; result : the :class:`~rodlab.calibrate.CalibrationResult`
    nominal_mm, calibrated_mm : shape=(M,) position error [mm] of each validation point with the nominal and
        the identified model, or ``None`` without validation points
    """

    robot: object
    campaign: object
    result: object
    nominal_mm: np.ndarray | None = None
    calibrated_mm: np.ndarray | None = None
    observations: object = None            # what was fitted (calibrate.Observations)
    options: dict | None = None            # the identification's options (for cross-validation)

    @property
    def before(self):
        """:class:`~rodlab.calibrate.validate.ErrorStats` of the nominal model (or ``None``)."""
        return None if self.nominal_mm is None else _stats(self.nominal_mm)

    @property
    def after(self):
        """... of the identified model (or ``None``)."""
        return None if self.calibrated_mm is None else _stats(self.calibrated_mm)


def _stats(errors_mm):
    from rodlab.calibrate.validate import error_stats
    return error_stats(errors_mm)


def run_calibration(args, rod: RodCompliance, compensation, camp=None) -> CalibrationRun:
    """Identification (+ validation) of one campaign with the rod's mass / tool from ``rod`` and the
    deflection offsets of ``compensation`` (:class:`rodlab.calibrate.Compensation`); ``camp`` the campaign
    already read (else ``args.campaign`` with ``args.device``)."""
    from rodlab.calibrate import ModelParams, campaign_observations, identify, read_fixture, read_points
    from rodlab.calibrate import validate
    robot = robot_from_args(args)
    fix = read_fixture(args.fixture)
    if camp is None:                                    # compare reads the campaign and warns once
        camp = campaign_from_args(args, robot.n)
        warn_flagged_fixture(fix, args.fixture)
    obs = campaign_observations(camp, fix, rod)
    options = dict(also_compensate=_thermal(args, camp, rod), pinned=_pins(args, robot.n), freed=set(args.free),
                   robust=args.robust, harmonics=getattr(args, "joint_harmonics", ()))
    from rodlab.calibrate.plausible import constrain_to_ranges
    noise = args.noise_um * 1e-3 if getattr(args, "noise_um", None) else DEVICE_NOISE_MM
    res, options["pinned"] = constrain_to_ranges(
        lambda pins: identify(robot, obs, rod.tool_mm, compensation.rod if compensation.active else None,
                              fix_unidentifiable=not args.strict, **(options | {"pinned": pins}),
                              expected_noise_mm=noise), options["pinned"], options["freed"])
    run = CalibrationRun(robot, camp, res, observations=obs, options=options)
    if args.validate:
        pts = read_points(args.validate, robot.n)
        run.nominal_mm = validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)[1]
        run.calibrated_mm = validate(robot, res.params, pts)[1]
    return run


def _thermal(args, camp, rod) -> tuple:
    """``--thermal DESIGN``: the rod's thermal growth as a further compensation (needs the campaign's temp_C)."""
    if not getattr(args, "thermal", None):
        return ()
    from rodlab.calibrate import ThermalGrowth

    from ...design_io import resolve_design
    if camp.temp_C is None or not np.all(np.isfinite(camp.temp_C)):
        raise RodlabError(f"{args.campaign}: --thermal needs the temperature of every point (a temp_C column [degC]); "
                          f"record it or leave --thermal out")
    design = resolve_design(args.thermal)
    if np.linalg.norm(np.asarray(design.tool_mm) - rod.tool_mm) > 1.0:
        print(f"warning: --thermal {args.thermal}: its tool vector {np.round(design.tool_mm, 1).tolist()} mm is not "
              f"the rod file's {np.round(rod.tool_mm, 1).tolist()} mm; is it the same rod?", file=sys.stderr)
    growth = ThermalGrowth.of_design(design, args.t_ref_c)
    log.info("thermal growth of the tool vector: %s um/K; temp_C %.2f..%.2f", np.round(growth.growth_T_mm_per_K * 1e3, 3),
             np.min(camp.temp_C), np.max(camp.temp_C))
    return (growth,)


def cmd_calibrate(args: argparse.Namespace) -> int:
    from rodlab.calibrate import result_dict
    if args.points and args.thermal:
        raise RodlabError("--thermal compensates a rod's growth during a campaign (its temp_C column); instrument "
                          "points (--points) have no rod to grow: leave --thermal out")
    if args.robot is None:
        if args.points or args.sockets:
            raise RodlabError(f"{'--points' if args.points else '--sockets'}: name the robot that made these readings "
                              "with --robot (a built-in name such as ur5, a robot TOML or a URDF); the tx90 default "
                              "is only for MultiCal campaigns")
        args.robot = "tx90"
    if (args.points or args.sockets) and args.device:
        raise RodlabError("--device converts a campaign's raw sensor readings; instrument points and socket readings "
                          "have none: leave --device out")
    if args.sockets and args.joint_harmonics:
        raise RodlabError("--joint-harmonics is for a campaign or instrument points; the socket fit (--sockets) has "
                          "no periodic joint errors: leave it out")
    if args.sockets:
        from .cmd_sockets import calibrate_sockets
        return calibrate_sockets(args)
    if args.points:
        return _calibrate_points(args)
    if not (args.campaign and args.fixture and args.rod):
        raise RodlabError("a campaign needs --fixture and --rod (or use --points for instrument data)")
    from rodlab.calibrate import Compensation
    rod = read_compliance(args.rod)
    comp = Compensation.of(None if args.compensation == "none" else rod)
    label = comp.label + ("+thermal" if args.thermal else "")
    run = run_calibration(args, rod, comp)
    robot, camp, res, before, after = run.robot, run.campaign, run.result, run.before, run.after
    _print_result(res, before, after, label)
    judge(res, _campaign_prediction(run, rod, comp))
    print_verdict(res)
    written = write_result_file(args, result_dict(robot, res, label, before, after))
    if args.png:
        from rodlab.calibrate.plots import plot_error_distributions, plot_residuals
        written.append(plot_residuals(res, camp, args.png))
        print(f"wrote {written[-1]}")
        if args.validate:
            errors = {"nominal": run.nominal_mm, f"calibrated ({label})": run.calibrated_mm}
            written.append(plot_error_distributions(errors, args.png))
            print(f"wrote {written[-1]}")
    write_command_report(args, written, default_folder(args))
    _note_uncompensated(robot, res, camp, args, rod, comp)
    if res.warnings:
        print_not_trusted(res)
        if res.residual_check is not None and res.residual_check.material:
            _print_suspects(robot, camp, args, rod, comp, res.residual_check)
        _note_ideal_device(args)
        return 3
    print_cautions(res)
    return 0


def _campaign_prediction(run: CalibrationRun, rod, comp):
    """The held-out accuracy: the validation points when given, else cross-validation over clamping positions."""
    from rodlab.calibrate.crossval import Prediction, cross_validate_identify
    if run.calibrated_mm is not None:
        return Prediction.of_validation(run.calibrated_mm, run.nominal_mm, run.result.rms_mm)
    return cross_validate_identify(run.robot, run.observations, rod.tool_mm, comp.rod if comp.active else None,
                                   fit_rms_mm=run.result.rms_mm, **run.options)


def _note_ideal_device(args) -> None:
    """A not-trusted raw campaign read with exactly orthogonal sensors: say that a real device's are not."""
    if not getattr(args, "device", None):
        return
    from rodlab.calibrate.device import read_device
    dev = read_device(args.device)
    if np.max(np.abs(dev.misalignment_deg())) < 1e-6:
        print(f"  - {args.device} states exactly orthogonal sensors (a design, not a device as built): a real "
              f"device's axes are off by up to a degree or two, which puts several um on readings a few tenths of "
              f"a mm from the datum; give the device's calibrated axes", file=sys.stderr)


def print_cautions(res) -> None:
    """A trusted result's cautions (residuals slightly above the noise model, partial-turn periodic terms)."""
    for c in res.cautions:
        print(f"caution (trusted): {c}", file=sys.stderr)


def print_not_trusted(res) -> None:
    """The reasons not to trust a result, and its cautions (which hold for a later, trusted fit too)."""
    print("NOT TRUSTED - do not load these parameters into the robot:", file=sys.stderr)
    for w in res.warnings:
        print(f"  - {w}", file=sys.stderr)
    for c in res.cautions:
        print(f"caution: {c}", file=sys.stderr)


def write_result_file(args, result: dict) -> list:
    """The result file when ``--json`` is given, else the result in memory (for ``--report``)."""
    from rodlab.calibrate import write_result
    if args.json:
        path = write_result(args.json, result)
        print(f"wrote {path}")
        return [path]
    from ..report import Source
    return [Source(result["format"], result)]


def _note_uncompensated(robot, res, camp, args, rod, comp) -> None:
    """With ``--compensation none`` and a file that has matrices: how far the uncompensated rod deflects."""
    if comp.active or not (rod.C_F.any() or rod.C_g.any()):
        return
    import numpy as np

    from rodlab.calibrate import campaign_observations, deflection_offsets, read_fixture
    obs = campaign_observations(camp, read_fixture(args.fixture), rod)
    off = deflection_offsets(robot, res.params, obs.q_rad, obs.force_W_N, rod)
    print(f"note: the rod's deflection is not compensated; by {args.rod} it moves the ball up to "
          f"{np.linalg.norm(off, axis=1).max() * 1e3:.0f} um in this campaign (--compensation file compensates it)")


def _print_suspects(robot, camp, args, rod, comp, test) -> None:
    """The campaign diagnosis (the same residual test ``test``, with its noise model, then the hypotheses) and
    what to do about each."""
    from rodlab.calibrate import read_fixture
    from rodlab.compliance import RodCompliance
    from rodlab.app.diagnose import diagnose_campaign
    from rodlab.app.diagnose.advice import remedy
    used = comp.rod if comp.active else RodCompliance.none_like(rod)
    diag, _ = diagnose_campaign(robot, camp, read_fixture(args.fixture), used, noise_mm=test.noise_mm,
                                fixture_sigma=test.fixture_sigma, harmonics=args.joint_harmonics)
    print(f"suspects (`rodlab diagnose --campaign`, verdict {diag.verdict}):", file=sys.stderr)
    for f in diag.findings:
        where = f" at {f.location}" if f.location else ""
        print(f"  - {f.effect}{where}: {remedy(f)}", file=sys.stderr)


def _print_result(res, before, after, label) -> None:
    print(f"identification ({label} compensation): {len(res.free)} parameters from {res.residuals_mm.shape[0]} "
          f"points, residual rms {res.rms_mm * 1e3:.2f} um per reading, {res.iterations} compensation passes, "
          f"{res.message}")
    print_parameters(res)
    if before is not None:
        print("  validation (base and tool refitted)   mean     max  median      SD  [mm]")
        for name, st in (("before (nominal)", before), ("after", after)):
            print(f"    {name:<34} {st.mean_mm:6.3f} {st.max_mm:7.3f} {st.median_mm:7.3f} {st.sd_mm:7.3f}")


def print_parameters(res) -> None:
    """The free parameters (value, sigma, unit, status), how many are held, and the residual test."""
    print(f"  {'parameter':<14} {'value':>14} {'sigma':>12}  unit       status")
    for nm in res.free:
        info = next(i for i in res.infos if i.name == nm)
        v, s = res.values[nm], res.sigma[nm]
        if info.unit == "rad/(N m)":
            print(f"  {nm:<14} {v * 1e6:14.3f} {s * 1e6:12.3f}  urad/(N m) {res.status[nm]}")
        else:
            print(f"  {nm:<14} {v:14.5f} {s:12.5f}  {info.unit:<10} {res.status[nm]}")
    print_held(res)
    if res.residual_check is not None:
        t = res.residual_check
        verdict = "NOT noise" if t.material else "slightly above noise" if t.missing else "consistent with noise"
        print(f"  residuals {verdict}: {res.residual_check.describe()}")


def _calibrate_points(args) -> int:
    from rodlab.calibrate import ModelParams, read_points, result_dict, validate
    from rodlab.calibrate.crossval import Prediction
    from rodlab.calibrate.points import cross_validate_points, identify_points, stated_noise_mm
    robot = robot_from_args(args)
    pts, noise_mm = stated_noise_mm(read_points(args.points, robot.n), args.noise_um * 1e-3 if args.noise_um else None)
    options = dict(pinned=_pins(args, robot.n), freed=args.free, robust=args.robust, harmonics=args.joint_harmonics)
    from rodlab.calibrate.plausible import constrain_to_ranges
    res, options["pinned"] = constrain_to_ranges(
        lambda pins: identify_points(robot, pts, noise_mm, fix_unidentifiable=not args.strict,
                                     **(options | {"pinned": pins})), options["pinned"], options["freed"])
    before = after = None
    errors = {}
    if args.validate:
        test = read_points(args.validate, robot.n)
        before, errors["nominal"], _ = validate(robot, ModelParams.nominal(robot, test.tool_mm), test)
        after, errors["calibrated"], _ = validate(robot, res.params, test)
    _print_result(res, before, after, "instrument points")
    judge(res, Prediction.of_validation(errors["calibrated"], errors["nominal"], res.rms_mm) if errors
          else cross_validate_points(robot, pts, res.rms_mm, **options))
    print_verdict(res)
    written = write_result_file(args, result_dict(robot, res, "none", before, after))
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


def _compare_runs(items) -> list:
    """(name, rod file, compensation) per ``--rod LABEL=FILE``, led by no compensation; checked before any run.
    A label is only a name: the file's matrices compensate whatever it is called (a file of method ``none``
    compensates nothing, and says so)."""
    from rodlab.calibrate import Compensation
    runs = []
    for item in items:
        label, eq, path = item.partition("=")
        if not eq or not label.strip() or not path.strip():
            raise RodlabError(f"--rod {item!r}: expected LABEL=FILE (e.g. fea=rod1.fea.compliance.json)")
        rod = read_compliance(path)
        if not runs:
            runs.append(("None", rod, Compensation.of(None)))
        if label.strip().lower() == "none" and rod.method.value != "none":
            raise RodlabError(f"--rod {item!r}: the label 'none' is the uncompensated run, which compare adds "
                              f"itself, but {path} is a {rod.method} file; label it by its method "
                              f"(e.g. {rod.method}={path})")
        if rod.method.value == "none":
            log.warning("--rod %s: a method-none file compensates nothing", item)
        runs.append((label.strip(), rod, Compensation.of(rod, label.strip())))
    return runs


def cmd_compare(args: argparse.Namespace) -> int:
    args.robot = args.robot or "tx90"
    if not args.validate:
        raise RodlabError("compare needs --validate FILE (the statistics come from the validation points); add the "
                          "campaign's *.validation.csv")
    planned = _compare_runs(args.rod)
    camp = campaign_from_args(args, robot_from_args(args).n)
    from rodlab.calibrate import read_fixture
    warn_flagged_fixture(read_fixture(args.fixture), args.fixture)
    runs = [(name, run_calibration(args, rod, comp, camp)) for name, rod, comp in planned]
    print(f"{'method':<10} {'Mean/[mm]':>10} {'Max/[mm]':>10} {'Median/[mm]':>12} {'SD/[mm]':>9} {'fit rms um':>11}")
    before = runs[0][1].before
    print(f"{'nominal':<10} {before.mean_mm:10.3f} {before.max_mm:10.3f} {before.median_mm:12.3f} {before.sd_mm:9.3f}")
    for name, run in runs:
        after = run.after
        print(f"{name:<10} {after.mean_mm:10.3f} {after.max_mm:10.3f} {after.median_mm:12.3f} {after.sd_mm:9.3f} "
              f"{run.result.rms_mm * 1e3:11.2f}")
    written = _write_comparison(args, runs)
    if args.png:
        from rodlab.calibrate.plots import plot_error_distributions
        errors = {"nominal": runs[0][1].nominal_mm} | {name: run.calibrated_mm for name, run in runs}
        written.append(plot_error_distributions(errors, args.png, "validation errors per compensation method"))
        print(f"wrote {written[-1]}")
    write_command_report(args, written, default_folder(args) if args.json or not args.png else Path(args.png).parent)
    return 0


def _write_comparison(args, runs: list) -> list:
    """The Table 3 of this campaign as ``rodlab.comparison/1`` (to ``--json``, else in memory for the report)."""
    from ..report import FORMAT_COMPARISON, Source
    methods = {"nominal": runs[0][1].before.to_dict()}
    for name, run in runs:
        methods[name] = dict(run.after.to_dict(), fit_rms_um=run.result.rms_mm * 1e3, trusted=not run.result.warnings)
    data = {"format": FORMAT_COMPARISON, "robot": runs[0][1].robot.name, "campaign": str(args.campaign),
            "fixture": str(args.fixture), "validation": str(args.validate), "methods": methods}
    if not args.json:
        return [Source(FORMAT_COMPARISON, data)]
    from ...fileio import atomic_write_json, json_safe
    path = atomic_write_json(args.json, json_safe(data))
    print(f"wrote {path}")
    return [path]


def register_more(sub) -> None:
    from .effectargs import effects_help
    from rodlab.calibrate.effects import CAMPAIGN_EFFECTS
    p = sub.add_parser("simulate-campaign", help="write a synthetic MultiCal campaign from a random truth robot",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="The project's own test data: a truth robot (random kinematic errors, joint "
                                   "compliances), a fixture, a rod, noise; writes the contract's campaign, fixture, "
                                   "validation and compliance files and a truth.json. Effects the calibrator's "
                                   "model leaves out and their parameters (defaults: a typical magnitude):\n"
                                   + effects_help(CAMPAIGN_EFFECTS))
    add_robot_options(p)
    p.add_argument("--rod", required=True, help="the rod's compliance file (nominal)")
    p.add_argument("--rod-true", default=None, help="the rod as it really is (default: --rod)")
    p.add_argument("--positions", type=count, default=5)
    p.add_argument("--orientations", type=count, default=6)
    p.add_argument("--noise-um", type=nonneg_float, default=3.0, help="device noise [um]")
    p.add_argument("--fixture-error", action="append", default=[], metavar="J:dx,dy,dz",
                   help="a wrong recorded pose: offset [mm] added to position J (the same as --effect "
                        "fixture_pose:position=J,offset_mm=dx;dy;dz)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="add an effect (repeatable), e.g. periodic_joint_error:joint=4,amp_deg=0.006, "
                        "thermal_drift:growth_ppm_per_s=0.03, rod_deflection:k=1.5, outliers:count=3")
    p.add_argument("--raw", action="store_true",
                   help="write the device's three raw sensor readings (s1_mm, s2_mm, s3_mm; --noise-um per reading) "
                        "and its file multical.device.json (as built: sensors 2 and 3 off by --misalign-deg, springs "
                        "whose force follows each reading); nominal.device.json is the orthogonal design")
    p.add_argument("--misalign-deg", type=nonneg_float, default=1.0,
                   help="with --raw: how far sensors 2 and 3 are off orthogonal, each in a drawn direction [deg]")
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.set_defaults(func=cmd_simulate_campaign)

    p = sub.add_parser("plan", help="choose rod orientations per clamping position by observability (O1)",
                       description="Reachable rod orientations at every clamping position (numeric IK within the "
                                   "joint limits), chosen to maximise the observability index O1; prints O1-O5 and "
                                   "writes the joint angles for the robot program.")
    add_robot_options(p)
    p.add_argument("--fixture", required=True)
    p.add_argument("--rod", required=True, help="a compliance file (tool, mass) or a *.rod.toml design")
    p.add_argument("-k", type=count, default=6, help="orientations per position")
    p.add_argument("--candidates", type=count, default=24)
    p.add_argument("--seed", type=seed, default=0)
    p.add_argument("-o", "--output", default=None, help="CSV of joint angles (position,point,q1..qn)")
    p.set_defaults(func=cmd_plan)
    from . import cmd_fixture                # the fixture's poses from probing (registered here: one campaign family)
    cmd_fixture.register(sub)


def cmd_simulate_campaign(args) -> int:
    from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
    robot = robot_from_args(args)
    rod = read_compliance(args.rod)
    rod_true = read_compliance(args.rod_true) if args.rod_true else None
    from rodlab.calibrate.effects import campaign_effect

    from .effectargs import parse_effect_specs
    effects = []
    for it in args.fixture_error:
        j, _, v = it.partition(":")
        try:
            pos, off = int(j), [float(x) for x in v.split(",")]
        except ValueError:
            pos, off = 0, []
        if pos < 1 or len(off) != 3 or not all(map(math.isfinite, off)):
            raise RodlabError(f"--fixture-error {it!r}: expected J:dx,dy,dz (a position and three finite offsets "
                              f"[mm]), e.g. 2:0.05,0,-0.02")
        effects.append(("fixture_pose", {"position": pos, "offset_mm": off}))
    effects += parse_effect_specs(args.effect, campaign_effect)
    spec = CampaignSpec(positions=args.positions, orientations=args.orientations, device_noise_mm=args.noise_um * 1e-3,
                        seed=args.seed)
    device = _simulated_device(args)
    truth = simulate_campaign(robot, rod, args.output, spec, rod_true=rod_true, effects=effects, device=device)
    print(f"wrote a {args.positions} x {args.orientations} campaign of {robot.name} with rod {rod.rod} to {args.output}")
    if device is not None:
        from rodlab.calibrate.device import ideal_device, write_device
        write_device(ideal_device(), Path(args.output) / "nominal.device.json")
        print(f"  raw sensor readings; device as built multical.device.json (sensor pairs off orthogonal by "
              f"{', '.join(f'{v:.2f}' for v in device.misalignment_deg())} deg), nominal.device.json the design")
    for e in truth["effects"]:
        names = [p.name for p in campaign_effect(e["effect"]).params]
        print("  effect " + e["effect"] + ": " + ", ".join(f"{k}={e[k]}" for k in names if k in e))
    return 0


def _simulated_device(args):
    """``--raw``: the device as built, its misalignment drawn from a generator of its own (the campaign's other
    draws stay those of the same seed)."""
    if not args.raw:
        return None
    from rodlab.calibrate.device import ideal_device, misaligned_device
    return misaligned_device(ideal_device(), args.misalign_deg, np.random.default_rng([args.seed, 2]))


def cmd_plan(args) -> int:
    from rodlab.calibrate import read_fixture
    from rodlab.calibrate.plan import plan_poses
    from rodlab.fileio import atomic_write_text
    robot = robot_from_args(args)
    fix = read_fixture(args.fixture)
    if str(args.rod).endswith(".toml"):
        from ...calc import calc_rod_compliance
        from ...design_io import load_design
        rod = calc_rod_compliance(load_design(args.rod))
    else:
        rod = read_compliance(args.rod)
    poses, obs = plan_poses(robot, fix, rod.tool_mm, args.k, args.candidates, args.seed, rod.mass_kg, rod.com_T_mm)
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
