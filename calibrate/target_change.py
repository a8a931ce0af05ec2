"""Instrument points whose target or tool changed part-way through the file (two reflectors, a re-mounted target).

A tracker file that joins the points of two targets (a trial: the public FANUC points of reflector N1, then those of
N2) cannot be fitted with one tool: the nominal model, base and tool registered from scratch, misses it by 156 mm
rms, and the identification is refused with the joint columns, the units or the robot file as the suspects. Each
part on its own fits the nominal model as well as any real data set (2-6 mm). :func:`target_change` looks for that
split: where the registered nominal misfit of the whole is gross (:data:`~calibrate.mixups.NOMINAL_GROSS_MM`) and no
joint-column mix-up explains it, the data rows are cut at each candidate row and both parts registered on their own;
a cut whose worse part fits under the gross level and under :data:`~calibrate.mixups.SCREEN_GAIN` of the whole is
named (:class:`~calibrate.mixup.Mixup` ``target_change``).
"""
from __future__ import annotations

import logging
from typing import Callable

import numpy as np

from .mixup import Mixup

__all__ = ["target_change", "MIN_PART_POINTS", "MAX_CUTS", "SEARCH_POINTS"]

log = logging.getLogger(__name__)

#: the fewest points a part may have (a registration fits 9 numbers; 10 points give 30 readings)
MIN_PART_POINTS = 10
#: cuts tried on a first pass over long files (then every row around the best)
MAX_CUTS = 40
#: points of each part a cut is judged on during the search (evenly spaced; the cut named is judged on all)
SEARCH_POINTS = 60


def _part(pts, lo: int, hi: int, cap: int | None = None):
    """The rows ``lo`` .. ``hi`` - 1 of ``pts``; at most ``cap`` of them, evenly spaced (the search's subsample)."""
    idx = np.arange(lo, hi)
    if cap is not None and len(idx) > cap:
        idx = idx[np.linspace(0, len(idx) - 1, cap).round().astype(int)]
    return pts.subset(idx)


def _worse_part(pts, k: int, misfit: Callable) -> float:
    """The larger registered nominal misfit [mm] of the rows before ``k`` and from ``k`` on, each part registered on
    at most :data:`SEARCH_POINTS` of its points (a long file's cut costs what a short one's does)."""
    N = len(pts.q_deg)
    return max(misfit(_part(pts, 0, k, SEARCH_POINTS)), misfit(_part(pts, k, N, SEARCH_POINTS)))


def _best_cut(pts, misfit: Callable) -> tuple[int, float]:
    """(the cut row, its worse part's misfit) over every admissible cut: a coarse pass, then every row near the best."""
    N = len(pts.q_deg)
    cuts = np.arange(MIN_PART_POINTS, N - MIN_PART_POINTS + 1)
    step = max(1, int(np.ceil(len(cuts) / MAX_CUTS)))
    coarse = {int(k): _worse_part(pts, int(k), misfit) for k in cuts[::step]}
    k0 = min(coarse, key=coarse.get)
    near = [int(k) for k in cuts if abs(int(k) - k0) < step and int(k) not in coarse]
    coarse.update({k: _worse_part(pts, k, misfit) for k in near})
    k = min(coarse, key=coarse.get)
    return k, coarse[k]


def target_change(pts, misfit: Callable, given_mm: float, gross_mm: float, gain: float) -> Mixup | None:
    """The data row (1-based) from which the instrument points ``pts`` fit the nominal model with another target or
    tool, or None. ``misfit(points)``: the registered nominal misfit [mm] of a part; ``given_mm``: the whole file's;
    named where the worse part fits under ``gross_mm`` and ``gain`` x ``given_mm``."""
    N = len(pts.q_deg)
    if N < 2 * MIN_PART_POINTS or not given_mm > gross_mm:
        return None
    k, _ = _best_cut(pts, misfit)
    parts = (misfit(_part(pts, 0, k)), misfit(_part(pts, k, N)))           # the cut named, judged on every point
    worse = max(parts)
    log.info("instrument points cut at data row %d: the worse part %.2f mm (the whole %.1f mm)", k + 1, worse, given_mm)
    if not worse <= min(gross_mm, gain * given_mm):
        return None
    return Mixup(None, None, max(parts), given_mm, target_change=(k + 1, *parts), given_is_nominal=True)
