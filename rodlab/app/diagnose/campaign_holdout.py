"""Each campaign finding checked on the validation points before it is advised.

A finding is selected on the campaign alone (delta BIC, the likelihood-ratio test, leave-one-point-out
cross-validation); the campaign's poses are a few clamping positions, so a term can fit them and still not carry
over to other poses: a periodic error of a joint fitted over part of a turn and applied outside it, a flexible
term absorbing a bending forearm. With validation points (``--validate``), every finding is left out of the
re-identification in turn; where the validation points are predicted clearly better without it (the mean error
lower by two standard errors of the paired per-point difference, and by at least 2 um and 5 % of it:
:func:`rodlab.calibrate.validate.clearly_worse`), the finding carries a caution and its advice says not to apply it. An IRB 4600
trial (a bending forearm) had a periodic error of joint 3 called "decisive" whose correction, applied as advised,
doubled the held-out error.
"""
from __future__ import annotations

import logging

import numpy as np

from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.validate import clearly_worse
from rodlab.core.enums import FindingKind

from .campaign_refit import after_errors, reidentify

__all__ = ["check_on_validation", "HELD_OUT_WORSE"]

log = logging.getLogger(__name__)

#: the evidence key a flagged finding carries (True)
HELD_OUT_WORSE = "held_out_worse"


def check_on_validation(robot, camp, fix, rod, ctx, findings: list, noise_mm: float, fixture_sigma, points,
                        with_all: np.ndarray) -> None:
    """Leave each finding out of the re-identification in turn and compare the validation errors with
    ``with_all`` (shape=(M,) [mm], every finding applied); a finding without which the points are predicted
    clearly better gets ``evidence[HELD_OUT_WORSE]``, the two means and a caution. Findings are edited in place."""
    physical = [f for f in findings if f.effect != FindingKind.UNEXPLAINED]
    if not physical:
        return
    for f in physical:
        others = [g for g in physical if g is not f]
        try:
            without = _errors_without(robot, camp, fix, rod, ctx, others, noise_mm, fixture_sigma, points)
        except CalibrationError as e:      # the campaign without it cannot be identified: no comparison
            log.info("campaign diagnosis: %s %s not checked on the validation points (%s)", f.effect, f.location, e)
            continue
        _judge(f, with_all, without)


def _errors_without(robot, camp, fix, rod, ctx, others, noise_mm, fixture_sigma, points) -> np.ndarray:
    """Validation errors [mm] of the campaign re-identified with ``others`` only (none: the plain identification)."""
    if not others:
        return after_errors(robot, ctx.result.params, {}, {}, points)
    res, fit = reidentify(robot, camp, fix, rod, ctx, others, noise_mm, fixture_sigma)
    return after_errors(robot, res.params, fit.joint_corrections_rad, fit.torque_corrections, points)


def _judge(f, with_all: np.ndarray, without: np.ndarray) -> None:
    f.evidence["validation_mean_with_mm"] = float(with_all.mean())
    f.evidence["validation_mean_without_mm"] = float(without.mean())
    worse = clearly_worse(with_all, without)
    f.evidence[HELD_OUT_WORSE] = bool(worse)
    if worse:
        log.debug("campaign diagnosis: %s %s worsens the validation (%.4f -> %.4f mm)", f.effect, f.location,
                  without.mean(), with_all.mean())
        note = (f"the validation points are predicted worse with it (mean {without.mean():.3f} mm without it, "
                f"{with_all.mean():.3f} mm with it)")
        f.evidence["caution"] = "; ".join(c for c in (f.evidence.get("caution"), note) if c)
