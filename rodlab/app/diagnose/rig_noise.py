"""The noise of one gauge reading, from the recording itself: the yardstick of every rig finding.

1. **Within the holds:** the pooled SD of the readings about a straight line in time in each (hold, gauge) with at
   least 3 readings (a drift or creep inside a hold is not noise).
2. **Between repeats**, when the holds give fewer than :data:`MIN_DOF` degrees of freedom (1-2 readings per hold):
   the scatter of the hold means of the same gauge, load axis, mass and branch over the repeats (a one-way
   analysis of variance; friction and drift between repeats make it an upper bound: fewer findings, not false
   ones).
3. **The gauges' quantisation** as a floor: readings on a grid of step ``q`` (a 1 um dial gauge) are at least
   ``q / sqrt(12)`` uncertain, even where every reading of a hold is the same.

A recording that allows none of these is refused with what to record instead.

:func:`isolated_glitches` (:mod:`rodlab.stiffness_rig.glitches`, shared with `rig fit`) finds single readings far
off their hold's line (a gauge's glitch, an electrical spike): one 0.5 mm reading among 10 000 had made the noise
5 um instead of 0.66 um and hidden a joint.

:func:`repeat_scatter` measures how much a model's hold means scatter over the repeats beyond their noise
(friction that varies from hold to hold, handling): random structure, unlike a misfit that every repeat shares
(:mod:`.rig_repeatability` tells the two apart).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.errors import RodlabError
from rodlab.stiffness_rig.glitches import GLITCH_Z, hold_line_residuals, isolated_glitches, reading_quantum
from rodlab.stiffness_rig.samples import RigSamples


__all__ = ["NoiseEstimate", "reading_noise", "isolated_glitches", "hold_line_residuals", "repeat_scatter",
           "repeated_hold_means", "detection_floor_mm", "gauge_scatter", "MIN_DOF", "GLITCH_Z", "CHI2_1_MEDIAN"]

#: degrees of freedom of the within-hold estimate below which the repeats are used too
MIN_DOF = 10


@dataclass(frozen=True)
class NoiseEstimate:
    """``sigma_mm``: SD of one reading [mm]; ``dof``: its degrees of freedom; ``source``: how it was estimated
    (``within holds``, ``within holds and between repeats``, with ``, quantisation floor`` when the gauges'
    step set it)."""

    sigma_mm: float
    dof: int
    source: str


def reading_noise(data: RigSamples) -> NoiseEstimate:
    """Estimate the noise of one reading of ``data`` (the module's three steps). Raises
    :class:`~rodlab.core.errors.RodlabError` when the recording cannot show it."""
    ss, dof = _within_holds(data)
    source = "within holds"
    if dof < MIN_DOF:
        ss_r, dof_r = _between_repeats(data)
        if dof_r:
            ss, dof, source = ss + ss_r, dof + dof_r, "within holds and between repeats"
    if dof == 0:
        raise RodlabError("the recording cannot show the gauges' noise: no hold has 3 or more readings and no hold "
                          "is repeated at the same mass; record at least 3 readings per hold (e.g. 10 Hz over a few "
                          "seconds) or repeat the series")
    sigma = float(np.sqrt(ss / dof))
    floor = reading_quantum(data.y) / np.sqrt(12.0)
    if floor > sigma:
        sigma, source = floor, source + ", quantisation floor"
    if not sigma > 0:
        raise RodlabError("every reading of each hold is the same and the readings show no gauge step: the noise "
                          "cannot be estimated; check that the displacement columns are the gauges' readings")
    return NoiseEstimate(sigma, int(dof), source)


def _within_holds(data: RigSamples) -> tuple[float, int]:
    """Residual sum of squares and degrees of freedom of a line in time in each (hold, gauge) of >= 3 readings."""
    resid, dof = hold_line_residuals(data)
    return float(np.nansum(resid ** 2)), dof


def repeated_hold_means(data: RigSamples, values: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(hold means of ``values``, readings per hold) of every set of holds that repeat one (gauge, load axis and
    sign, mass, branch), two holds or more; the series' zeroing holds left out."""
    keep = ~data.reference
    if not keep.any():
        return []
    d, v = data.subset(keep), np.asarray(values, float)[keep]
    group = np.unique(np.column_stack([d.comp, d.axis, d.sign, np.round(d.mass, 6), d.unload]),
                      axis=0, return_inverse=True)[1].ravel()
    out = []
    for g in np.unique(group):
        m = group == g
        steps, inv, counts = np.unique(d.step[m], return_inverse=True, return_counts=True)
        if steps.size >= 2:
            out.append((np.bincount(inv.ravel(), weights=v[m]) / counts, counts))
    return out


def _between_repeats(data: RigSamples) -> tuple[float, int]:
    """Between-hold sum of squares (each hold mean weighted by its readings) and degrees of freedom of the holds
    that repeat one (:func:`repeated_hold_means`)."""
    ss, dof = 0.0, 0
    for means, counts in repeated_hold_means(data, data.y):
        grand = float((means * counts).sum() / counts.sum())
        ss += float((counts * (means - grand) ** 2).sum())
        dof += means.size - 1
    return ss, dof


def repeat_scatter(data: RigSamples, resid: np.ndarray, sigma: float) -> float:
    """The robust reduced chi-square of the hold means of ``resid`` (a model's residual of each reading [mm]) about
    the mean of the holds that repeat them (gauge, load axis and sign, mass, branch), each against its noise
    ``sigma**2 / readings``: ~1 when the holds repeat to within their noise, whatever misfit they share; the
    median over the holds (divided by chi-square(1)'s median), so one stray hold does not set it. 1 when nothing
    repeats."""
    z2 = []
    for means, counts in repeated_hold_means(data, resid):
        k = means.size
        grand = float(np.average(means, weights=counts))           # holds of unequal length weigh as they inform
        z2 += list((means - grand) ** 2 / (sigma ** 2 / counts) * k / (k - 1))
    return max(float(np.median(z2)) / CHI2_1_MEDIAN, 1.0) if z2 else 1.0


#: holds repeated fewer times than this (the median) leave the hold scatter's floor on every reading
FLOOR_REPEATS = 3


#: one gauge's hold scatter this many times the recording's (a median over all gauges) is scatter on that gauge,
#: which the selection's sigma does not carry
GAUGE_SPREAD = 4.0


def gauge_scatter(data: RigSamples, resid: np.ndarray, sigma: float) -> float:
    """The largest of the gauges' own :func:`repeat_scatter` of ``resid`` [mm]."""
    comp = np.asarray(data.comp)
    return max((repeat_scatter(data.subset(comp == c), np.asarray(resid)[comp == c], sigma)
                for c in np.unique(comp)), default=1.0)


def detection_floor_mm(data: RigSamples, sigma: float, scatter: float = 1.0, gauge_max: float | None = None) -> float:
    """The noise [mm] a term's change of the readings is seen against: one reading's ``sigma``, or a hold mean's
    scatter (``sigma sqrt(scatter / n)``, n the median hold's readings, ``scatter`` :func:`repeat_scatter`) where
    that is larger; not the selection's per-reading ``sigma sqrt(scatter)``, which puts a hold mean's scatter on
    every reading. The floor stays ``sigma sqrt(scatter)`` with fewer than :data:`FLOOR_REPEATS` repeats of a hold
    (the scatter cannot be told from structure: the independent rig simulator's 2-repeat friction had then been
    given a drift) and where one gauge scatters :data:`GAUGE_SPREAD` times more than the recording
    (``gauge_max``, :func:`gauge_scatter`: the selection's sigma, a median over the gauges, does not carry it, and a
    review's 1 um on one gauge had been given a drift, a friction and a crosstalk)."""
    if scatter > 1.0 and (_median_repeats(data) < FLOOR_REPEATS
                          or (gauge_max is not None and gauge_max > GAUGE_SPREAD * scatter)):
        return float(sigma * np.sqrt(scatter))
    keys = np.asarray(data.step, np.int64) * 4 + np.asarray(data.comp, np.int64)
    n = float(np.median(np.unique(keys, return_counts=True)[1])) if keys.size else 1.0
    return float(sigma * max(1.0, np.sqrt(max(scatter, 1.0) / max(n, 1.0))))


def _median_repeats(data: RigSamples) -> float:
    """The median number of repeats of the holds that repeat one (:func:`repeated_hold_means`), 1 for none."""
    sizes = [means.size for means, _ in repeated_hold_means(data, np.zeros(np.size(data.y)))]
    return float(np.median(sizes)) if sizes else 1.0


#: the median of a chi-square of one degree of freedom
CHI2_1_MEDIAN = 0.4549364


