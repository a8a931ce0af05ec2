"""What to do about a campaign finding: the ``rodlab calibrate`` options or the measurement that removes it.

``rodlab calibrate`` prints these when its residual test (:mod:`calibrate.residual_test`) says physics is
missing: it runs the campaign diagnosis (the same test, then the hypotheses) and names each suspect with
its remedy, so an untrusted result always says what to do next.
"""
from __future__ import annotations

from .report import Finding

__all__ = ["remedy"]


def _fixture(f: Finding) -> str:
    j = f.location.split(":")[1]
    frees = " ".join(f"--free fixture_{j}_{k}" for k in "xyz")
    return (f"re-measure clamping position {j}'s pose, or identify its offset with the robot: re-run "
            f"`rodlab calibrate` with {frees}")


def _rod(f: Finding) -> str:
    k = f.parameters.get("k")
    if k is None:
        return ("the rod's deflection is not compensated: calibrate with the rod's compliance file "
                "(`--rod FILE --compensation file`; `rodlab fea` or `rodlab rig fit` make one)")
    return (f"the compliance file is off by a factor {k:.3g}: measure the rod on the stiffness rig "
            "(`rodlab rig fit` writes a measured file) and calibrate with that file")


def _outliers(f: Finding) -> str:
    return (f"re-measure points {f.location.split(':')[1]} (a gross alignment error), or calibrate with "
            "--robust to down-weight them")


_REMEDIES = {
    "fixture_pose": _fixture,
    "rod_deflection": _rod,
    "outliers": _outliers,
    "periodic_joint_error": lambda f: (f"joint {f.location.split(':')[1]} has a once-per-revolution angle error the "
                                       "kinematic model does not hold: have the gearbox / encoder checked, or "
                                       "compensate it in the controller with the fitted amplitudes"),
    "thermal_drift": lambda f: ("the robot grew during the campaign: let it warm up to a steady temperature and "
                                "record the campaign again (or shorter)"),
    "unexplained": lambda f: ("no modelled cause: check the device's mounting and the fixture for play, record "
                              f"more points at {f.location or 'the worst position'}, and compare with the "
                              "simulated campaign of `rodlab simulate-campaign`"),
}


def remedy(f: Finding) -> str:
    """One sentence: what to do about ``f`` (an effect of the campaign vocabulary)."""
    make = _REMEDIES.get(f.effect)
    return make(f) if make else f"see docs/diagnose.md for {f.effect}"
