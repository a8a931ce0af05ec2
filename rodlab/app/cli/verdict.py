"""The calibration verdict as the CLI states it: *usable?* (the held-out accuracy against the nominal model, and
the fit's own checks; exit 3 when not) and *complete?* (what the model leaves unexplained against the
instrument's noise), printed as two separate statements (:mod:`rodlab.calibrate.trust`)."""
from __future__ import annotations

import sys

from rodlab.calibrate.trust import (campaign_excess, completeness_statement, prediction_cautions, prediction_warnings,
                                   validated_excess)

__all__ = ["judge", "accept_validated", "print_verdict", "print_held"]


def judge(res, prediction) -> None:
    """Record the held-out ``prediction`` (or None) on ``res`` and add its reasons not to use the result, and the
    caution of a prediction along one-joint sweeps only."""
    res.prediction = prediction
    res.warnings = list(res.warnings) + prediction_warnings(prediction)
    res.cautions = list(res.cautions) + prediction_cautions(prediction)


def accept_validated(res, robots_own) -> bool:
    """A campaign's residual excess made a caution instead of a reason where independent validation points show
    the calibration predicts clearly better than the nominal model
    (:func:`~rodlab.calibrate.trust.validated_excess`) and ``robots_own()`` (the campaign diagnosis, called only
    then) puts the excess on the robot's own physics, not on the files; returns whether it did."""
    validated = validated_excess(res, res.prediction)
    excess = campaign_excess(res)
    if not validated or excess not in res.warnings or not robots_own():
        return False
    res.warnings.remove(excess)
    res.cautions = list(res.cautions) + [validated]
    return True


def print_verdict(res) -> None:
    """The two statements on stdout: usable? (with the predicted accuracy) and complete?."""
    pred = res.prediction
    acc = pred.describe() if pred is not None and pred.points else "no held-out prediction"
    if res.warnings:
        why = _short(res.warnings[0]) + (f" (and {len(res.warnings) - 1} more)" if len(res.warnings) > 1 else "")
        print(f"  usable? no, because {why}: see NOT TRUSTED below; {acc}")
    else:
        print(f"  usable? yes: {acc}")
    print(f"  {completeness_statement(res)}")
    print(f"verdict: {'NOT TRUSTED' if res.warnings else 'TRUSTED'}")


def _short(reason: str, limit: int = 90) -> str:
    """A reason's first clause (to its first colon or semicolon, without a parenthesis that clause leaves open),
    at most ``limit`` characters."""
    head = reason.replace(";", ":").split(":", 1)[0].strip()
    if head.count("(") > head.count(")"):
        head = head[:head.rfind("(")].rstrip()
    return head if len(head) <= limit else head[:limit - 3].rstrip() + "..."


def print_held(res) -> None:
    """The parameters held at nominal because these data cannot separate them, with the reason."""
    held = [u for u in res.unidentifiable if any(w in u for w in ("in this", "has no effect", "too little"))]
    print(f"  held at nominal: {len(res.unidentifiable)} ({len(held)} that these data cannot separate"
          + (": " if held else "") + "; ".join(held[:12]) + (" ..." if len(held) > 12 else "") + ")"
          + ("; the rest by rule or pin, see --json" if len(res.unidentifiable) > len(held) else ""))
    if held:
        print(f"note: {len(held)} parameter(s) held at nominal because these data cannot separate them "
              "(--strict refuses the data set instead)", file=sys.stderr)
