"""Calibrate the frame model on a design family (one tube / bend / sleeve set, any L1 x L2) from solid FEA.

The global calibration (:data:`fea.frame.CALIBRATION`) is a compromise over many materials and joints; on
random designs it can be several per cent off (docs/fea.md). Within a family the joints are the same and only
the free tube lengths change, so one solid run of one member, cut at its free tubes, gives each joint's own
flexibility (:mod:`fea.joints`), which every other member takes over: within 0.35 % on the paper's families
and 10 hard random families (``scripts/frame_random_blind.py``).

:func:`joint_fit_member` picks the member to solve: the base, unless its free tubes are too short to cut
``margin`` diameters from their ends (then the grid's nearest member that has them).
"""
from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.errors import RodlabError

from .joints import DEFAULT_MARGIN, MIN_SPAN_MM, free_spans

__all__ = ["joint_fit_member", "calibration_member"]

log = logging.getLogger(__name__)


def _fits(design: RodDesign, margin: float) -> bool:
    """Both free tubes hold two sections ``margin`` diameters from their ends, ``MIN_SPAN_MM`` apart."""
    spans = free_spans(design)
    return all(spans[p][1] - spans[p][0] >= 2 * margin * t.outer_diameter_mm + MIN_SPAN_MM
               for p, t in ((Part.PIPE_I, design.pipe_I), (Part.PIPE_II, design.pipe_II)))


def joint_fit_member(base: RodDesign, L1s=(), L2s=(), margin: float = DEFAULT_MARGIN) -> RodDesign:
    """The family member whose solid run calibrates the family: ``base`` if its free tubes are long enough
    for the joint fit's sections, else the valid L1 x L2 grid design nearest to it (relative distance
    ``|dL1| / L1 + |dL2| / L2``) that is; ``base`` if none is (a coarser calibration, logged)."""
    if _fits(base, margin):
        return base
    best, best_d = None, np.inf
    for L1 in np.asarray(L1s, dtype=float):
        for L2 in np.asarray(L2s, dtype=float):
            try:
                d = replace(base, L1_mm=float(L1), L2_mm=float(L2), name=f"{base.name} {L1:g}-{L2:g}")
            except RodlabError:
                continue
            dist = abs(L1 - base.L1_mm) / base.L1_mm + abs(L2 - base.L2_mm) / base.L2_mm
            if dist < best_d and _fits(d, margin):
                best, best_d = d, dist
    if best is None:
        log.warning("no member of %s's family in the grid has free tubes of %g diameters at each end; "
                    "calibrating on the base with shorter margins", base.name, margin)
        return base
    log.info("%s's free tubes are too short for the joint calibration: calibrating on %s", base.name, best.name)
    return best


#: the name before "calibration" was kept for the robot's (kept for callers)
calibration_member = joint_fit_member
