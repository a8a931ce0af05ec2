"""Whether a validated campaign's residual excess is the robot's own (a caution) or the files' (a refusal): the
campaign diagnosis run with the calibration's noise model, and a clamping pose looked for directly."""
from __future__ import annotations

from rodlab.calibrate.fixture_check import fixture_suspect
from rodlab.calibrate.identify import STRICT_HINT
from rodlab.core.compliance import RodCompliance
from rodlab.core.errors import RodlabError

from .calibration_run import CalibrationRun
from .deviceargs import points_from_args

__all__ = ["ROBOT_PHYSICS", "campaign_diagnosis", "robots_own", "pose_off"]


#: campaign findings of the robot's own physics outside the model: the excess a validation may be trusted through
ROBOT_PHYSICS = frozenset({"periodic_joint_error", "joint_stiffening", "lost_motion", "thermal_drift",
                           "joint_zero_shift"})


def campaign_diagnosis(run: CalibrationRun, args, comp):
    """(the campaign diagnosis, None) with the calibration's residual test's noise model, each finding checked on
    the validation points where there are some; or (None, why it cannot run: it identifies every parameter, the
    calibration held some at nominal)."""
    from rodlab.app.diagnose import diagnose_campaign
    test = run.result.residual_check
    used = run.rod_file if comp.active else RodCompliance.none_like(run.rod_file)
    points = points_from_args(args, args.validate, run.robot) if args.validate else None
    try:
        diag, _ = diagnose_campaign(run.robot, run.campaign, run.fixture, used, noise_mm=test.noise_mm,
                                    validate_points=points, fixture_sigma=test.fixture_sigma,
                                    harmonics=args.joint_harmonics)
    except RodlabError as e:
        return None, str(e).replace(STRICT_HINT, "")
    return diag, None


def robots_own(diagnosis) -> bool:
    """Whether the campaign ``diagnosis`` (:func:`campaign_diagnosis`) puts a validated campaign's residual excess
    on the robot's own physics (:data:`ROBOT_PHYSICS`) and on nothing of the files (a clamping pose, the device, the
    rod file, stray points), so the excess is a caution (a review: a clamping position recorded 0.3 mm off had been
    trusted through a validation file: the diagnosis names it ``fixture_pose`` where the robot's own errors leave it
    visible). What no effect explains counts as the robot's own too: a robot's repeatability, a backlash below the
    detection limit, a periodic error once modelled, link masses off (an independent trial's good calibrations had
    been refused for them, validated 0.03-0.06 mm against 0.77 nominal); where it lies (at one position, evenly)
    is no guide on such a robot (the trial's excess lay at position 1 with the right fixture file and evenly with
    a pose 0.3 mm off), so the validation decides and the excess is printed with what to check."""
    diag, _ = diagnosis
    if diag is None:
        return False
    effects = {str(f.effect) for f in diag.findings}
    return not effects - ROBOT_PHYSICS - {"unexplained"} - HELD_OUT_TELLS


#: findings of the files a validation's held-out points show the calibration works through: a few stray points
#: (a calibration engineer's trial: two outliers beside a gear error and thermal growth had refused a calibration
#: validated 1.167 -> 0.155 mm; printed with what to do under "what the model leaves out")
HELD_OUT_TELLS = frozenset({"outliers"})


def pose_off(run: CalibrationRun) -> bool:
    """Whether a clamping position's recorded pose looks off (:func:`~rodlab.calibrate.fixture_check.fixture_suspect`:
    its translation freed takes half the sum of squares away), its reason put first on the result (a review: a
    pose 0.3 mm off had been trusted through a validation file on a robot with errors of its own)."""
    found = fixture_suspect(run.robot, run.observations, run.rod, run.compensations, run.options, run.result)
    if found is not None:
        run.result.warnings.insert(0, found.reason())
    return found is not None
