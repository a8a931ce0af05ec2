"""What to do about a campaign finding: the ``rodlab calibrate`` options or the measurement that removes it.

``rodlab calibrate`` prints these when its residual test (:mod:`calibrate.residual_test`) says physics is
missing: it runs the campaign diagnosis (the same test, then the hypotheses) and names each suspect with
its remedy (each campaign effect's module states it: :mod:`rodlab.calibrate.effects`), so an untrusted result
always says what to do next.
"""
from __future__ import annotations

from rodlab.calibrate.effects import campaign_effect
from rodlab.calibrate.trust import GROSS_CAUSES, NOISY_FILE_CAUSES, PLAUSIBLE_NOISE_FACTOR, gross, implausible_device

from ...core.enums import FindingKind
from ...core.errors import RodlabError
from ...core.units import DEVICE_NOISE_MM
from .campaign_holdout import HELD_OUT_WORSE
from .report import Finding

__all__ = ["remedy"]


def _unexplained(f: Finding) -> str:
    if f.parameters.get("spread") == "even" and gross(f.parameters.get("birge_ratio", 0.0),
                                                      f.parameters.get("rms_mm", 0.0)):
        return (f"no device is {f.parameters['birge_ratio']:.0f} times noisier than stated, so do not raise "
                f"--noise-um: the files do not describe this campaign: check {GROSS_CAUSES}")
    if f.parameters.get("spread") == "even" and _implausible_device(f):
        return (f"no structure by position or time, but a scatter of {f.parameters['scatter_um']:.1f} um is no "
                f"MultiCal device's (more than {PLAUSIBLE_NOISE_FACTOR:g} times its {DEVICE_NOISE_MM * 1e3:g} um), so "
                f"do not raise --noise-um: check the files first ({NOISY_FILE_CAUSES}), then the robot and the fixture "
                "for play no effect models (backlash in a wrist joint, a loose ball, device or mount)")
    if f.parameters.get("spread") == "even":
        return ("no structure by position or time: a device noisier than stated would give this, and so would the "
                "robot's own repeatability or a backlash too small to name; if the device's specification or a "
                "repeatability test (the ball held still, read 30 times) shows a scatter of at least "
                f"{f.parameters['scatter_um']:.1f} um, state it with --noise-um; otherwise the excess is the robot's "
                "or structure no effect models: validation points (--validate) show whether the calibration works "
                "through it; check the device's mounting and sensors, the ball and the fixture for play")
    if f.parameters.get("spread") == "time":
        return ("the residuals change through the campaign: let the robot run warm to a steady temperature before "
                "the campaign (log temp_C), check the device and the fixture for settling, and record again or "
                "shorter; a noisier device would not give this")
    where = f.location or "the worst position"
    return (f"no modelled cause: check {where}'s clamping pose in the fixture file (a pose recorded off shows there "
            f"first), the device's mounting and the fixture for play, record more points at {where}, and compare "
            "with the simulated campaign of `rodlab simulate-campaign`")


def _implausible_device(f: Finding) -> bool:
    """The excess would need a device no MultiCal device is (:func:`~calibrate.trust.implausible_device`)."""
    return implausible_device(float(f.parameters.get("scatter_um", 0.0)) * 1e-3)


def remedy(f: Finding) -> str:
    """One sentence: what to do about ``f`` (an effect of the campaign vocabulary: its module's remedy)."""
    if f.effect == FindingKind.UNEXPLAINED:
        return _unexplained(f)
    if f.evidence.get(HELD_OUT_WORSE):
        joint = (f.location or "").startswith("joint:")
        device = str(f.effect).startswith("device_")
        turn = " and turns that joint over its range" if joint else ""
        check = (" (a device's finding: check its file against the device, and its reading columns' order and signs)"
                 if device else "")
        return ("do not apply it" + ("" if device else " to the robot") + ": it fits the campaign's poses, not the "
                f"validation's; record a campaign that covers the poses the robot works in{turn} and diagnose it "
                f"again{check}")
    if f.effect == "periodic_joint_error" and "span_deg" in f.parameters and _validation_helped(f):
        return _confirmed_harmonics(f)
    try:
        model = campaign_effect(f.effect)
    except RodlabError:
        return f"see docs/diagnose.md for {f.effect}"
    return model.remedy(f.location, f.parameters)


#: a finding "helps" the validation where its points' mean error with it is at most this share of the one without
HELPED_SHARE = 0.8


def _validation_helped(f: Finding) -> bool:
    """Whether the validation points, checked with and without ``f`` (:mod:`.campaign_holdout`), are predicted
    clearly better with it."""
    ev = f.evidence
    if ev.get(HELD_OUT_WORSE) is not False or "validation_mean_with_mm" not in ev:
        return False
    return ev["validation_mean_with_mm"] <= HELPED_SHARE * ev["validation_mean_without_mm"]


def _confirmed_harmonics(f: Finding) -> str:
    """A periodic joint error the validation points confirm: identify it (a calibration engineer's trial: over
    273 deg of joint 3 it had been advised against, where the validation went 0.155 -> 0.038 mm with it)."""
    j = (f.location or "").partition(":")[2]
    ev, span = f.evidence, f.parameters.get("span_deg")
    held = (f" over the {span:.0f} deg of joint {j} this campaign turned (a smooth error of the joint fits there too: "
            "the terms hold over that range only)") if span is not None else ""
    times = ("once- and twice" if "amp_sin_rad" in f.parameters else "twice") if "amp2_sin_rad" in f.parameters \
        else "once"
    return (f"the validation points confirm the {times}-per-revolution error (mean "
            f"{ev['validation_mean_without_mm']:.3f} mm without it, "
            f"{ev['validation_mean_with_mm']:.3f} mm with it): identify it with the robot (`rodlab calibrate "
            f"--joint-harmonics {j}`, checked again on the validation points){held} and compensate it in the "
            "controller, or have the gearbox / encoder checked")
