"""One campaign identified (and checked on validation points): shared by ``rodlab calibrate`` and ``rodlab compare``."""
from __future__ import annotations

import logging
import sys
from dataclasses import dataclass, field, replace

import numpy as np

from rodlab.calibrate import (FitOptions, ModelParams, Rod, ThermalGrowth, campaign_observations, identify, read_fixture,
                              validate)
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.points import stated_noise_mm
from rodlab.calibrate.residual_test import residual_test
from rodlab.calibrate.trust import implausible_device, stated_noise_warning
from rodlab.calibrate.kinematics import HARMONICS
from rodlab.calibrate.validate import error_stats
from rodlab.calibrate.compensations import compensation_label

from ...core.compliance import RodCompliance
from ...core.design_io import resolve_design
from ...core.errors import RodlabError
from ...core.units import DEVICE_NOISE_MM
from .calibrateargs import pins_from_args
from .deviceargs import campaign_from_args, flagged_fixture_reasons, points_from_args, warn_flagged_fixture
from .columnsargs import screen_joint_columns
from .robotargs import robot_from_args

__all__ = ["run_calibration", "CalibrationRun"]

log = logging.getLogger(__name__)


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
    rod: object = None                     # the rod on the flange (calibrate.Rod)
    compensations: list = field(default_factory=list)   # what the fit removed (calibrate.compensations entries)
    options: object = None                 # the identification's options (calibrate.FitOptions; cross-validation)
    fixture: object = None                 # the fixture file as read (calibrate.Fixture)
    rod_file: object = None                # the compliance file as read (core.compliance.RodCompliance)
    without_harmonics_mm: np.ndarray | None = None   # with --joint-harmonics and --validate: the validation errors
    #                                                  [mm] of the same calibration without the periodic terms
    validation_noise_mm: float | None = None          # the validation points' instrument noise per coordinate [mm]

    @property
    def label(self) -> str:
        """What the result calls its compensation (e.g. ``fea``, ``none``, ``calc+thermal``)."""
        return compensation_label(self.compensations)

    @property
    def before(self):
        """:class:`~rodlab.calibrate.validate.ErrorStats` of the nominal model (or ``None``)."""
        return None if self.nominal_mm is None else _stats(self.nominal_mm)

    @property
    def after(self):
        """... of the identified model (or ``None``)."""
        return None if self.calibrated_mm is None else _stats(self.calibrated_mm)


def _stats(errors_mm):
    return error_stats(errors_mm)


def run_calibration(args, rod: RodCompliance, deflection, camp=None) -> CalibrationRun:
    """Identification (+ validation) of one campaign with the rod (tool, mass, COM) of the file ``rod``, its
    deflection compensated by ``deflection`` (:class:`rodlab.calibrate.RodDeflection`) and, with ``--thermal``,
    its thermal growth; ``camp`` the campaign already read (else ``args.campaign`` with ``args.device``)."""
    robot = robot_from_args(args)
    fix = read_fixture(args.fixture)
    if camp is None:                                    # compare reads the campaign and warns once
        camp = campaign_from_args(args, robot)
        warn_flagged_fixture(fix, args.fixture)
    pts = points_from_args(args, args.validate, robot) if args.validate else None
    if pts is not None:                                 # before the campaign's fit, not after it
        screen_joint_columns(args, robot, pts, args.validate)
    obs = campaign_observations(camp, fix, rod)
    compensations = [deflection, *_thermal(args, camp, rod)]
    options = FitOptions(pinned=pins_from_args(args, robot.n), freed=set(args.free), robust=args.robust,
                         harmonics=getattr(args, "joint_harmonics", ()), fix_unidentifiable=not args.strict,
                         expected_noise_mm=args.noise_um * 1e-3 if getattr(args, "noise_um", None) else DEVICE_NOISE_MM)
    from rodlab.calibrate.plausible import constrain_to_ranges
    res, pins = constrain_to_ranges(lambda p: identify(robot, obs, Rod.of(rod), compensations, replace(options, pinned=p)),
                                    options.pinned, options.freed)
    options = replace(options, pinned=pins)       # with the range holds: the cross-validation fits the same model
    if args.strict:
        _refuse_regularised(res, args.campaign)
    if res.warnings:                              # not trusted: a flagged probing is the first place to look
        res.warnings[:0] = flagged_fixture_reasons(fix, args.fixture)
    run = CalibrationRun(robot, camp, res, observations=obs, rod=Rod.of(rod), compensations=compensations, fixture=fix,
                         rod_file=rod,
                         options=options)
    if pts is not None:
        run.validation_noise_mm = stated_noise_mm(pts, None)[1]
        run.nominal_mm = validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)[1]
        run.calibrated_mm = validate(robot, res.params, pts)[1]
        if options.harmonics:             # the periodic terms checked on the held-out points before they are used
            run.without_harmonics_mm = _without_harmonics(robot, obs, rod, compensations, options, pts)
    return run


def _refuse_regularised(res, path) -> None:
    """``--strict``: refuse a campaign whose free parameters include ones these data cannot identify (status
    ``regularised``: sigma from the data alone beyond the parameter's physical size, the value its prior's), naming
    them (a calibration engineer's trial: c_4-c_6 said not identifiable had passed --strict as TRUSTED)."""
    weak = [nm for nm in res.free if res.status[nm] == "regularised"]
    if weak:
        raise RodlabError(f"{path}: --strict: {', '.join(weak)} cannot be identified from these data (sigma beyond "
                          "the parameter's physical size: the fit would keep them at their start values); for joint "
                          "compliances measure the same poses under other loads (the rod's own weight at other arm "
                          "postures, a payload), for geometric parameters more poses spread over the workspace "
                          "(`rodlab plan`); or pin them (--pin NAME=VALUE), or drop --strict to keep them at their start "
                          "values, reported as regularised")


def _without_harmonics(robot, obs, rod, compensations, options, pts) -> np.ndarray | None:
    """Validation errors [mm] of the same identification without the periodic terms (their pins and frees left
    out too), or None when it is refused (the check is then skipped, with a note)."""
    keep = [n for n in options.pinned if n.rpartition("_")[0] not in HARMONICS]
    plain = replace(options, harmonics=(), pinned={n: options.pinned[n] for n in keep},
                    freed=frozenset(n for n in options.freed if n.rpartition("_")[0] not in HARMONICS))
    try:
        res = identify(robot, obs, Rod.of(rod), compensations, plain)
    except CalibrationError as e:
        print(f"note: the calibration without --joint-harmonics, which the periodic terms are checked against on "
              f"the validation points, was refused ({e}); that check is skipped", file=sys.stderr)
        return None
    return validate(robot, res.params, pts)[1]


def _thermal(args, camp, rod) -> tuple:
    """``--thermal DESIGN``: the rod's thermal growth as a further compensation (needs the campaign's temp_C)."""
    if not getattr(args, "thermal", None):
        return ()
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


def stated_noise_reason(run: CalibrationRun, args) -> str | None:
    """:func:`~rodlab.calibrate.trust.stated_noise_warning` of a campaign's calibration (None with
    ``--noise-checked``): where a stated --noise-um no MultiCal device has passed the residual test, the same test at
    the device's own noise decides."""
    test = run.result.residual_check
    if getattr(args, "noise_checked", False) or test is None or not test.clamping or not implausible_device(test.noise_mm):
        return None
    at_device = residual_test(run.robot, run.result, run.observations, DEVICE_NOISE_MM, test.fixture_sigma)
    return stated_noise_warning(test, at_device)
