"""Rig physics outside the effect vocabulary that the diagnosis still models, so that it is not forced onto a
vocabulary effect that mimics it: a found one makes the verdict ``unexplained`` with its place.

- a gauge's own non-linearity: the reading of gauge c is ``v (1 + k_c v)`` instead of ``v`` (a displacement
  sensor off its linear range). On the gauge's dominant load axis it is the curve of a load non-linearity on
  that axis; it differs on the other load axes, where the same gauge reads a displacement of its own (C_F's
  off-diagonal terms), and on the other gauges, which it leaves alone. Gauges of one type off their range
  alike (one k on every gauge, location ``sensor:all``) curve each reading in proportion to its own size,
  where a load non-linearity curves every axis alike in the load.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.enums import FindingKind
from rodlab.core.hypothesis import Hypothesis

__all__ = ["outside_hypotheses", "OUTSIDE", "confirm_outside"]

#: the effect name of a hypothesis outside the vocabulary (its finding is reported as ``unexplained``)
OUTSIDE = FindingKind.UNEXPLAINED
_AXES = "xyz"


def outside_hypotheses(data, base: np.ndarray) -> list[Hypothesis]:
    """One gauge non-linearity per measured gauge, and one common to every gauge (gauges of one type, one k);
    ``base`` (n,) the simulated reading of each sample [mm]."""
    out = []
    gauges = sorted(set(data.comp.tolist()))
    for c in gauges:
        col = np.where(data.comp == c, base ** 2, 0.0)
        out.append(Hypothesis(OUTSIDE, f"sensor:{_AXES[c]}", ["k_per_mm"], col[:, None], [-1.0], [1.0],
                              f"the {_AXES[c]} gauge's reading is not linear in the displacement (a reading "
                              f"scaled by 1 + k v): a property of the gauge, outside the effect vocabulary"))
    if len(gauges) > 1:
        # on a rod whose axes differ in compliance the curvature follows each gauge's reading, not the load: a
        # load non-linearity on every axis with crosstalk would otherwise mimic it with three terms
        out.append(Hypothesis(OUTSIDE, "sensor:all", ["k_per_mm"], (base ** 2)[:, None], [-1.0], [1.0],
                              "every gauge's reading is not linear in the displacement, alike (readings scaled by "
                              "1 + k v: gauges of one type off their linear range): outside the effect vocabulary"))
    return out


def confirm_outside(location: str | None) -> str | None:
    """What would confirm an outside finding at ``location`` (None: not one of this module's)."""
    if location and location.startswith("sensor:"):
        g = location.split(":", 1)[1]
        which = "each gauge" if g == "all" else f"the {g} gauge"
        return (f"check {which} against reference displacements over its range (gauge blocks, a calibrated "
                f"micrometer): its own non-linearity shows there, a load non-linearity of the rod does not")
    return None
