"""Readings no rod on the rig can give: a gauge's readings far beyond everything the recording's holds span.

An instrument trial's dial gauge was switched to inches for 3 s: 22 readings of two holds read ~-11.5 mm where the
rod deflects 0.1 mm in the whole recording, and `rig fit` and the diagnosis refused the recording as having "no load
response" (the glitch rule, :mod:`.glitches`, takes single readings off a hold's line, not a run of them). Such a
reading lies farther from its gauge's typical level than :data:`GROSS_FACTOR` times the span of the gauge's hold
levels (and at least :data:`GROSS_MIN_MM`): not the rod, not the rig. Where they are few (at most
:data:`GROSS_SHARE_MAX` of the gauge's readings) they are left out and said with their time span; more are the
recording's problem, left to the checks that follow.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .recording import RigRecording

__all__ = ["GrossReadings", "gross_readings", "without_gross", "GROSS_FACTOR", "GROSS_MIN_MM", "GROSS_SHARE_MAX"]

#: a reading this many times the span of its gauge's hold levels from the gauge's typical level is no rod's
GROSS_FACTOR = 20.0
#: ... and at least this far [mm] (a rod in the rig deflects tenths of a millimetre)
GROSS_MIN_MM = 0.5
#: at most this share of a gauge's readings are left out as gross (more: the recording's problem, said elsewhere)
GROSS_SHARE_MAX = 0.15
_AX = "xyz"


@dataclass
class GrossReadings:
    """The readings left out as gross.

    rows, comps : shape=(k,) recording rows and gauge components (0-2); level_mm : shape=(k,) the typical level of
    each one's gauge in its series [mm]; span_mm : shape=(k,) the span of that gauge's hold levels there [mm];
    time_s : shape=(k,) the readings' times [s]; value_mm : shape=(k,) the readings [mm]
    """

    rows: np.ndarray
    comps: np.ndarray
    level_mm: np.ndarray
    span_mm: np.ndarray
    time_s: np.ndarray
    value_mm: np.ndarray

    @property
    def any(self) -> bool:
        return self.rows.size > 0

    def text(self) -> str:
        parts = []
        for c in np.unique(self.comps):
            m = self.comps == c
            off = float(np.median(np.abs(self.value_mm[m] - self.level_mm[m])))
            parts.append(f"{int(m.sum())} reading(s) of the {_AX[c]} gauge at {self.time_s[m].min():.1f}-"
                         f"{self.time_s[m].max():.1f} s lie ~{off:.3g} mm from its other readings, where its hold "
                         f"levels span {float(np.max(self.span_mm[m])) * 1e3:.0f} um in their series")
        return ("; ".join(parts) + ": no rod or rig gives that (a unit switched on the gauge, the gauge lifted off "
                "the rod or knocked, a misread answer); left out")


def gross_readings(rec: RigRecording) -> GrossReadings:
    """The readings of ``rec`` beyond :data:`GROSS_FACTOR` x their gauge's span of hold levels within their series
    (a run of one load axis: the gauges are zeroed at its start, so each series has its own level; see the
    module)."""
    rows, comps, levels, spans = [], [], [], []
    series = rec.series()
    for c in range(3):
        for k in np.unique(series):
            ok = np.nonzero(np.isfinite(rec.disp_mm[:, c]) & (series == k))[0]
            if ok.size < 20:
                continue
            y = rec.disp_mm[ok, c]
            medians = np.array([np.median(y[rec.step[ok] == s]) for s in np.unique(rec.step[ok])])
            lo, hi = np.percentile(medians, [15, 85])        # a hold of gross readings does not widen the span
            level, span = float(np.median(medians)), float(hi - lo)
            far = np.abs(y - level) > max(GROSS_FACTOR * span, GROSS_MIN_MM)
            if 0 < far.sum() <= GROSS_SHARE_MAX * ok.size:
                rows.append(ok[far])
                comps.append(np.full(int(far.sum()), c))
                levels.append(np.full(int(far.sum()), level))
                spans.append(np.full(int(far.sum()), span))
    cat = (lambda v, dt=float: np.concatenate(v) if v else np.zeros(0, dt))  # noqa: E731
    r, k = cat(rows, int), cat(comps, int)
    return GrossReadings(r, k, cat(levels), cat(spans), rec.time_s[r], rec.disp_mm[r, k])


def without_gross(rec: RigRecording) -> tuple[RigRecording, GrossReadings]:
    """(``rec`` with its gross readings blanked, what was left out)."""
    gross = gross_readings(rec)
    if not gross.any:
        return rec, gross
    return rec.without_readings(gross.rows, gross.comps), gross
