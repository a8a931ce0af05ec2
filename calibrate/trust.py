"""Whether to trust a calibration, as two separate statements.

*Usable?* (the verdict, exit 3 when not): the fit converged, has degrees of freedom to spare, its parameters are
physically plausible, it predicts held-out points clearly better than the nominal model
(:class:`~calibrate.crossval.Prediction`: the validation set, else cross-validation) and not much worse than it
fits its own (overfitting); for a MultiCal campaign, whose model covers every physical effect of the device,
residuals well above the device's noise also fail it (a wrong clamping pose or a noisier device than stated
biases every parameter). *Complete?* (:func:`completeness`): whether the model explains the readings down to the
instrument's noise; a real robot's never quite does (gear errors, link and joint deflection, temperature), so for
instrument points and socket readings an incomplete model is a caution on a usable result, not a reason to
refuse it."""
from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from rodlab.core.enums import AccuracySource, Completeness
from rodlab.core.units import DEVICE_NOISE_MM

from .residual_test import BIRGE_MATERIAL
from .robot_toml import row_key_line

if TYPE_CHECKING:
    from .crossval import Prediction
    from .result import CalibrationResult

__all__ = ["rms_text", "trust_warnings", "bound_warnings", "trust_cautions", "prediction_warnings", "completeness",
           "completeness_statement",
           "unmodelled_gross", "typical_miss_mm", "stated_noise_warning", "implausible_device",
           "PLAUSIBLE_NOISE_FACTOR", "NOISY_FILE_CAUSES",
           "ERROR_BOUNDS", "MIN_READINGS_PER_PARAMETER", "OVERFIT_RATIO", "OVERFIT_SHARE", "USUAL_MOVE",
           "prediction_cautions", "campaign_excess", "validated_excess"]


#: physical bounds of the identified errors; beyond them a result is flagged
ERROR_BOUNDS = {"dtheta": 2.0, "d": 10.0, "a": 10.0, "alpha": 2.0, "beta": 2.0}
#: physical range of a joint compliance [rad/(N m)] and how far below 0 an estimate is still zero (a parameter
#: outside it by less than its uncertainty is held at the range's end and refitted: :mod:`calibrate.plausible`)
C_LOW, C_HIGH, C_TOLERANCE = 0.0, 1e-4, 1e-6
#: scalar readings per free parameter below which a fit has too few degrees of freedom to be judged
MIN_READINGS_PER_PARAMETER = 2.0
#: held-out rms per coordinate over the fit's rms per reading above which the parameters may fit noise: about 1
#: for many exchangeable points (the UR5 grid: 1.01), 1.7 for a TX90 campaign's 30 points in interleaved folds and
#: 2.7 predicting a clamping position from the other four (an extrapolation)
OVERFIT_RATIO = 3.0
#: ... and overfitting only when the held-out mean error also keeps more than this share of the nominal model's:
#: a held-out error several times a 3 um fit is harmless while it is a hundredth of the nominal's
OVERFIT_SHARE = 0.5



def rms_text(mm: float, decimals: int = 1) -> str:
    """A residual [mm] as printed: in um below a millimetre (``decimals`` after the point), in mm above (a gross
    fit had printed 404644.9 um)."""
    return f"{mm * 1e3:.{decimals}f} um" if mm < 1.0 else f"{mm:.4g} mm"

def trust_warnings(robot, res: "CalibrationResult") -> list[str]:
    """Reasons not to use a calibration that the fit itself shows: no convergence, too few degrees of freedom,
    for a MultiCal campaign residuals the noise model does not explain by a material margin (Birge ratio above
    :data:`~calibrate.residual_test.BIRGE_MATERIAL`; :mod:`calibrate.residual_test`, the test ``rodlab diagnose
    --campaign`` uses too), parameters beyond physical bounds. The predicted accuracy adds its own
    (:func:`prediction_warnings`)."""
    w = []
    if not res.success:
        w.append(f"the Levenberg-Marquardt run did not converge ({res.message})")
    w += _dof_warnings(res)
    test = res.residual_check
    excess = campaign_excess(res)
    if excess:
        w.append(excess)
    typical = typical_miss_mm(res)
    if test is not None and not test.clamping and unmodelled_gross(test.birge, typical):
        w.append(f"the calibrated model misses half the readings by more than {typical:.1f} mm ({res.rms_mm:.1f} mm rms, "
                 f"{test.birge:.0f} times the {test.source}'s stated scatter): no robot's unmodelled physics leaves "
                 f"this much after a calibration (real robots' tracker data: 0.04-0.65 mm rms), so the readings do not "
                 f"describe this robot: check {UNMODELLED_GROSS_CAUSES}")
    return w + bound_warnings(robot, res)


def campaign_excess(res: "CalibrationResult") -> str | None:
    """The reason a MultiCal campaign's residuals above the device's noise give not to use it (None where they
    are noise): a wrong clamping pose, a noisier device, another rod's file or the robot's own errors outside the
    model each bias every parameter; files that do not fit together (:func:`gross`) say so."""
    test = res.residual_check
    if test is None or not test.material or not test.clamping:
        return None
    causes = ("the robot's own errors outside the model (a periodic joint error, backlash, thermal growth), a wrong "
              "clamping pose, a noisier device or a rod file that is not this rod"
              if not gross(test.birge, res.rms_mm) else
              f"not a noisier device ({res.rms_mm * 1e3:.0f} um rms per reading against the stated "
              f"{test.noise_mm * 1e3:.1f} um) but files that do not describe this campaign: {GROSS_CAUSES}")
    return (f"residuals ({rms_text(res.rms_mm)} rms) are not noise: {test.describe()}; the model covers the "
            f"device's physics, so this is {causes}, and it biases every parameter: run `rodlab diagnose --campaign` "
            "on the same files to find which" + ("" if gross(test.birge, res.rms_mm) else
                                                 ", and validate on independent points (--validate)"))


def validated_excess(res: "CalibrationResult", pred: "Prediction | None") -> str | None:
    """A campaign's residual excess (:func:`campaign_excess`, not gross) that independent validation points show
    the calibration still predicts clearly better than the nominal model through: usable as validated, with this
    caution (a real robot always has errors outside the model: a device trial's periodic joint error and backlash
    had been NOT TRUSTED while its validation fell from 0.572 to 0.119 mm; the paper's own campaigns leave a
    robot floor of ~0.27 mm). None where the excess stays a reason not to use it."""
    test = res.residual_check
    if (campaign_excess(res) is None or gross(test.birge, res.rms_mm) or pred is None
            or pred.source is not AccuracySource.VALIDATION or not pred.clearly_better()):
        return None
    return (f"the model is incomplete: the residuals ({rms_text(res.rms_mm)} rms) are not the device's noise "
            f"({test.describe()}): the robot's own errors outside the model (a periodic joint error, backlash, "
            "thermal growth), or a wrong clamping pose, a noisier device or another rod's file, bias the parameters; "
            "the independent validation points show the calibration predicts clearly better than the nominal model "
            "all the same, so it is usable at the validated accuracy: `rodlab diagnose --campaign` names what is left "
            "out (e.g. a periodic error for --joint-harmonics)")


def typical_miss_mm(res: "CalibrationResult") -> float:
    """The median distance [mm] of a reading from the calibrated model (residual vector norm): a few outliers, which
    a robust fit or a diagnosis handles, do not move it; a column mix-up moves most readings."""
    r = np.asarray(res.residuals_mm, float)
    return float(np.median(np.linalg.norm(r.reshape(len(r), -1), axis=1))) if r.size else 0.0


def unmodelled_gross(birge: float, typical_mm: float) -> bool:
    """Whether instrument points' or socket readings' misfit after calibration is beyond any physics a real robot
    adds to its model: their median miss (:func:`typical_miss_mm`) beyond :data:`UNMODELLED_GROSS_RMS_MM` and the
    Birge ratio beyond :data:`GROSS_BIRGE`."""
    return typical_mm >= UNMODELLED_GROSS_RMS_MM and birge >= GROSS_BIRGE


def _moved(robot, res: "CalibrationResult", info) -> float:
    """How far a geometric parameter was identified from the robot file's nominal row [its unit] (``dtheta`` is the
    offset error itself)."""
    nominal = {"d": robot.d_mm, "a": robot.a_mm, "alpha": robot.alpha_deg, "beta": robot.beta_deg}
    v = res.values[info.name]
    return v if info.kind == "dtheta" else v - nominal[info.kind][info.index]


def _metres_hint(robot, info, value: float) -> str:
    """Where a length identified ~1000 x its nominal row's value: that row looks given in metres (a calibration
    engineer's trial: d_4 = -0.670 in a robot file in mm had read as d_4 moved -670 mm)."""
    if info.kind not in ("a", "d"):
        return ""
    nominal = float((robot.d_mm if info.kind == "d" else robot.a_mm)[info.index])
    if nominal == 0.0 or not 500.0 <= value / nominal <= 2000.0:
        return ""
    return (f"; the robot file's {info.name} = {nominal:g} looks like metres (the data put it at {value:.4g} mm): "
            f"give it in mm ({1000 * nominal:g})")


def bound_warnings(robot, res: "CalibrationResult") -> list[str]:
    """Identified parameters beyond physical bounds: a geometric error no manufacturing leaves
    (:data:`ERROR_BOUNDS` from the nominal), a joint compliance no gearbox has."""
    w = []
    for info in res.infos:
        if res.status[info.name] == "fixed":
            continue
        v = res.values[info.name]
        if info.kind in ERROR_BOUNDS:
            err = _moved(robot, res, info)
            if abs(err) > ERROR_BOUNDS[info.kind]:
                w.append(f"{info.name} moved {err:+.3g} {info.unit} from nominal (bound {ERROR_BOUNDS[info.kind]:g}): "
                         f"not a plausible manufacturing error" + _metres_hint(robot, info, v))
        if info.kind == "c" and not (C_LOW - C_TOLERANCE <= v <= C_HIGH):
            w.append(f"{info.name} = {v:.3g} +- {res.sigma[info.name]:.2g} rad/(N m) is outside [{C_LOW:g}, {C_HIGH:g}] by "
                     "more than its uncertainty can explain: not a plausible gearbox compliance")
    return w


def _dof_warnings(res: "CalibrationResult") -> list[str]:
    readings, P = res.residuals_mm.size, len(res.free)
    if P >= readings:
        return [f"{P} parameters from {readings} readings leave no degree of freedom to test the fit against: "
                "measure more points or identify fewer parameters (e.g. fewer --joint-harmonics)"]
    if readings < MIN_READINGS_PER_PARAMETER * P:
        return [f"{P} parameters from {readings} readings leave {readings - P} degrees of freedom, fewer than the "
                f"parameters (at least {MIN_READINGS_PER_PARAMETER:g} readings per parameter are needed to tell a "
                "fit from its noise): measure more poses spread over the workspace or identify fewer parameters"]
    return []


def prediction_warnings(pred: "Prediction | None") -> list[str]:
    """Reasons not to use a calibration that its predicted accuracy shows: no held-out prediction could be made,
    it is not clearly better than the nominal model's (2 standard errors of the paired difference), or the
    held-out error is far above the fit's (:data:`OVERFIT_RATIO`)."""
    if pred is None:
        return []
    if pred.points == 0:
        why = "; ".join(pred.failed[:2])
        return [f"no held-out prediction could be made: the identification was refused on every fold ({why}): "
                "measure more poses"]
    w = []
    if not pred.clearly_better():
        w.append(f"it does not predict clearly better than the nominal model: {pred.describe()}")
    if pred.overfit_ratio > OVERFIT_RATIO and pred.mean_mm > OVERFIT_SHARE * pred.nominal_mean_mm:
        w.append(f"the held-out error ({pred.rms_per_coordinate_mm * 1e3:.1f} um rms per coordinate) is "
                 f"{pred.overfit_ratio:.1f} times the fit's ({pred.fit_rms_mm * 1e3:.1f} um) and "
                 f"{pred.mean_mm / pred.nominal_mean_mm:.0%} of the nominal model's: the parameters fit these points "
                 "rather than the robot (overfitting); measure more poses or identify fewer parameters")
    return w


def prediction_cautions(pred: "Prediction | None") -> list[str]:
    """What a usable prediction holds for: along one-joint sweeps only, where the cross-validation held out poses
    inside the sweeps (:data:`~calibrate.crossval.SWEEP_GROUPING`)."""
    from .crossval import SWEEP_GROUPING                          # cycle: crossval imports this module's users
    if pred is None or pred.grouping != SWEEP_GROUPING or not pred.points:
        return []
    return ["the poses turn one joint at a time about one configuration, so the held-out accuracy holds along those "
            "sweeps only; elsewhere in the workspace it is not tested (a trial's FANUC fit, trusted at 0.22 mm that "
            "way, missed another recording of the same robot by 1.17 mm against the nominal model's 1.14): check it "
            "on varied poses (`rodlab plan`, or another recording with --validate) before relying on it there"]


def completeness(res: "CalibrationResult") -> Completeness | None:
    """Whether the model explains the readings to the noise (``None`` without a residual test)."""
    test = res.residual_check
    if test is None:
        return None
    return (Completeness.INCOMPLETE if test.material else Completeness.NEARLY if test.missing
            else Completeness.COMPLETE)


def completeness_statement(res: "CalibrationResult") -> str:
    """The *complete?* statement: how much the model leaves unexplained against the instrument's noise."""
    test = res.residual_check
    if test is None:
        return "complete? not tested (no noise level stated)"
    if not test.testable:
        return (f"complete? not tested: {test.dof} degree(s) of freedom are too few for the residuals to show what the "
                "model leaves out")
    word = {Completeness.COMPLETE: "yes", Completeness.NEARLY: "nearly", Completeness.INCOMPLETE: "no"}
    return (f"complete? {word[completeness(res)]}: the model leaves {rms_text(res.rms_mm)} rms per reading "
            f"unexplained (Birge ratio sqrt(chi-square / dof) {test.birge:.1f} by the residual test above, against "
            + (f"the device's {test.noise_mm * 1e3:.1f} um per reading and the clamping poses' uncertainty)"
               if test.clamping else f"the {test.source}'s noise {test.noise_phrase()} per reading)"))


#: residuals this large [mm rms] and this many times the stated scatter are no device's noise and no physics a
#: campaign misses (backlash, thermal growth, a gear error give tens of um) but files that do not fit together
GROSS_RMS_MM = 0.2
GROSS_BIRGE = 20.0
#: instrument points or socket readings a calibration leaves this far off [mm, the median reading] (and GROSS_BIRGE
#: times their scatter) are no real robot's unmodelled physics (the public tracker data: UR5 0.04-0.06, UR10 0.24, a FANUC
#: R-2000iC 0.65 mm) but readings of another robot's joints: two q columns exchanged had been TRUSTED at 24 mm
UNMODELLED_GROSS_RMS_MM = 5.0
#: what makes them so
UNMODELLED_GROSS_CAUSES = ("the q columns against the robot file's joints (order, signs, zero offsets), the units, "
                           "whether the robot file is this robot's, and whether the target or tool changed part-way "
                           "through the file (two reflectors, a re-mounted target: calibrate each part on its own)")
#: what makes them so
GROSS_CAUSES = ("the robot file's joints against the campaign's q columns (order, signs, zero offsets), the units "
                "(readings in mm, joint angles in deg, fixture poses in mm and deg), another rod's compliance file, "
                "or a fixture file of another layout")


#: a device noise stated (``--noise-um``) or implied (a diagnosis's even excess) beyond this factor times a MultiCal
#: device's (:data:`~rodlab.core.units.DEVICE_NOISE_MM`: the paper's sensors, 3 um accuracy) is no device's scatter:
#: a trial's campaign with its y column negated passed the residual test at 87 um (29x) and was TRUSTED, 6.5x less
#: accurate than with the column right; another campaign's fixture file at 96 um
PLAUSIBLE_NOISE_FACTOR = 5.0
#: what makes a MultiCal campaign's residuals look like a far noisier device
NOISY_FILE_CAUSES = ("a reading column's sign or order (the device's channels), a fixture file of another campaign "
                     "(its clampings' recorded orientations), the units of the readings and the fixture")


def implausible_device(scatter_mm: float) -> bool:
    """A device noise [mm] (stated, or one a diagnosis's even excess would need) beyond
    :data:`PLAUSIBLE_NOISE_FACTOR` times a MultiCal device's: no device's scatter."""
    return scatter_mm > PLAUSIBLE_NOISE_FACTOR * DEVICE_NOISE_MM


def stated_noise_warning(test, at_device) -> str | None:
    """The reason not to trust a MultiCal campaign whose residual test ``test`` passed at a stated device noise no
    MultiCal device has (:func:`implausible_device`) while the same test at the device's own noise ``at_device``
    (:func:`~calibrate.residual_test.residual_test` with :data:`~rodlab.core.units.DEVICE_NOISE_MM` and the same
    clamping-pose uncertainty) finds the residuals material; None otherwise (also for instrument points or socket
    readings: ``test.clamping`` False; a good campaign judged cautiously at 16-40 um stays trusted)."""
    if test is None or at_device is None or not test.clamping or not implausible_device(test.noise_mm):
        return None
    if not at_device.material:
        return None
    return (f"the residuals pass the test only at the stated device noise of {test.noise_mm * 1e3:.1f} um, "
            f"{test.noise_mm / DEVICE_NOISE_MM:.0f} times a MultiCal device's {DEVICE_NOISE_MM * 1e3:.1f} um (at which "
            f"they are {at_device.birge:.0f} times the expected scatter): no such device scatters that much, so the "
            f"files may not describe this campaign: check {NOISY_FILE_CAUSES}; if a repeatability test of this device "
            "(the ball held still, read 30 times) really shows that scatter, give --noise-checked")


def gross(birge: float, rms_mm: float) -> bool:
    """Whether a campaign's misfit (its Birge ratio, its residuals' rms [mm]) is beyond any device noise or missing
    physics: :data:`GROSS_RMS_MM` and :data:`GROSS_BIRGE` both exceeded."""
    return rms_mm >= GROSS_RMS_MM and birge >= GROSS_BIRGE


def trust_cautions(res: "CalibrationResult", robot=None) -> list[str]:
    """What a usable result should be read with: residuals above the noise model (for instrument points and
    socket readings also by a material margin: the model is incomplete), periodic joint errors identified
    over part of a turn, and (given the ``robot``) geometry moved farther from the robot file than a robot's
    manufacturing leaves."""
    return (_residual_caution(res) + _incomplete_caution(res) + _partial_turn_cautions(res)
            + (_large_move_cautions(robot, res) if robot is not None else []))


#: how far an identified length [mm] or angle [deg] usually lies from a robot's data sheet (its manufacturing
#: error: the real UR5, UR10 and FANUC sets move their lengths by <= 0.7 mm and their angles by <= 0.7 deg);
#: farther, within :data:`ERROR_BOUNDS`, the robot file itself may be wrong
USUAL_MOVE = {"d": 2.0, "a": 2.0, "alpha": 1.0, "beta": 1.0}


def _large_move_cautions(robot, res: "CalibrationResult") -> list[str]:
    """One caution naming the lengths and angles identified beyond :data:`USUAL_MOVE` from the robot file (a trial:
    a_2 typed 5 mm off was identified back and trusted without a word, the gain over 'nominal' inflated)."""
    moved = []
    for info in res.infos:
        if info.kind in USUAL_MOVE and res.status[info.name] == "identified":    # a regularised one is the prior's
            err = _moved(robot, res, info)
            beyond = abs(err) - USUAL_MOVE[info.kind]
            if 0 < beyond and beyond > 3 * res.sigma[info.name] and abs(err) <= ERROR_BOUNDS[info.kind]:
                nominal = res.values[info.name] - err
                moved.append(f"{info.name} {err:+.2f} {info.unit} (from {round(nominal, 6):g}"
                             f"{_file_line(robot, info)})")
    if not moved:
        return []
    held = [u.split(" ")[0] for u in res.unidentifiable if "in this data set" in u]
    also = (f", or what the parameters held at nominal ({', '.join(held)}) leave for these to carry" if held else "")
    return [f"{', '.join(moved)}: farther from the robot file ({robot.name}) than a robot's manufacturing usually "
            f"leaves (~{USUAL_MOVE['a']:g} mm, ~{USUAL_MOVE['alpha']:g} deg): check those rows of the robot file (a "
            f"typo, another variant of the robot{also}); the improvement over its nominal model is then partly the "
            f"file's"]


def _file_line(robot, info) -> str:
    """``, robot.toml line 23`` where the robot file is a TOML file with the parameter's own key, else ``""``."""
    line = None if robot.path is None else row_key_line(robot.path, info.index, info.kind)
    return f", {robot.path.name} line {line}" if line else ""


#: what an incomplete model of instrument readings may miss, by the kind of reading (ResidualTest.source)
_CAUSES = {
    "instrument": "either the instrument is noisier than stated (check --noise-um against its specification) or the "
                  "model misses physics a real robot has (gear and encoder errors, backlash, link deflection, "
                  "temperature): `rodlab diagnose --points` on the same files names what it can",
    "seat": "either the ball sits less exactly than stated (# seat_sigma_mm, or --noise-um) or the model misses "
            "physics (joint backlash, the arm bending under the hand that pushed the ball in, a worn socket)",
    "ball-bar length": "either the ball bar reads less exactly than stated (# length_sigma_mm, or --noise-um) or the "
                       "model misses physics (joint backlash, the bar's pivot moving)",
}


def _incomplete_caution(res: "CalibrationResult") -> list[str]:
    test = res.residual_check
    if test is None or not test.material or test.clamping:
        return []
    return [f"the model is incomplete: it leaves {rms_text(res.rms_mm)} rms per reading unexplained "
            f"(Birge ratio {test.birge:.1f} against the stated noise {test.noise_phrase()} per reading); "
            f"{_CAUSES.get(test.source, _CAUSES['instrument'])}. The predicted accuracy already includes what is "
            "left out"]


#: a periodic error identified over less than this span of its joint's reading [deg] is cautioned (one period of
#: the first harmonic: over less, an IRB 4600 trial's bending forearm fitted as joint 3's harmonics over 235 deg
#: doubled the held-out error, 0.049 -> 0.109 mm)
PARTIAL_TURN_DEG = 360.0


def _partial_turn_cautions(res: "CalibrationResult") -> list[str]:
    return [f"joint {j}'s periodic error was identified over {lo:.0f}..{hi:.0f} deg of its reading, less than a "
            f"turn: there any smooth error of the joint (a bending link, a gear that stiffens with the torque) fits "
            f"it as well and its terms extrapolate; it describes the error there, not over the gear's whole turn: do "
            f"not use it outside that range, and check it on validation points (--validate) against a calibration "
            f"without --joint-harmonics"
            for j, (lo, hi) in sorted(res.harmonic_range_deg.items()) if hi - lo < PARTIAL_TURN_DEG]


def _residual_caution(res: "CalibrationResult") -> list[str]:
    test = res.residual_check
    if test is None or not test.missing or test.material:
        return []
    return [f"residuals are slightly above the noise model: {test.describe()}; the scatter is {test.birge:.2f} "
            f"times the model's (trusted up to {BIRGE_MATERIAL:g}: what is left out moves the points by about the "
            f"noise, and the standard errors above come from the residuals' own scatter); "
            + ("`rodlab diagnose --campaign` looks for a cause" if test.clamping else
               "check --noise-um against the instrument's specification")]
