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
    try:
        model = campaign_effect(f.effect)
    except RodlabError:
        return f"see docs/diagnose.md for {f.effect}"
    return model.remedy(f.location, f.parameters)
