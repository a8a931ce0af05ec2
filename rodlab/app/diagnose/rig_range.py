"""Readings of a gauge at the end of its range: a displacement sensor that has reached its stop reads one value
whatever the rod does (outside the effect vocabulary, and no property of the rod or the rig).

A gauge whose extreme reading recurs, to the last digit, over the holds of two or more different loads has stopped
there: an elastic rod gives two loads two readings. So has one whose holds at the extreme read one value to the last
digit, noise-free, in two or more holds while its other holds scatter (a stop reached by the largest load
alone). Those holds of the gauge are left out of the diagnosis and named
(``unexplained`` at ``sensor:K``); fitted, a clipped gauge had been named a load non-linearity with a joint and a
tare beside it. Readings near zero (a gauge across an axis with no cross-compliance) are never a stop: the
extreme must be at least :data:`RANGE_MIN_SD` noise SDs.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.enums import FindingKind
from rodlab.stiffness_rig.samples import RigSamples

from .report import Finding

__all__ = ["at_range_limit", "range_finding", "RANGE_MIN_SD"]

#: a stop's reading is at least this many noise SDs of one reading from zero
RANGE_MIN_SD = 10.0
#: a hold sits at the stop when this share of its readings of the gauge equal the extreme
_HOLD_SHARE = 0.8
_AXES = "xyz"


def at_range_limit(data: RigSamples, sigma: float) -> np.ndarray:
    """The readings (bool, shape=(n,)) of gauges that sat at a stop (see the module docstring); ``sigma`` the
    noise of one reading [mm]."""
    out = np.zeros(data.n, dtype=bool)
    for c in np.unique(data.comp):
        on = data.comp == c
        for extreme in (np.max(data.y[on]), np.min(data.y[on])):
            if abs(extreme) < RANGE_MIN_SD * sigma:
                continue
            at = on & (np.abs(data.y - extreme) <= 1e-9)
            held = _holds_at(data, on, at)
            loads = {load for _, load in held}
            if len(loads) >= 2 or (len(held) >= 2 and _others_scatter(data, on, sigma, {s for s, _ in held})):
                # the whole hold of the gauge: its readings just below the stop are biased low too
                out |= at | (on & np.isin(data.step, [s for s, _ in held]))
    return out


def _holds_at(data: RigSamples, on: np.ndarray, at: np.ndarray) -> list:
    """(step, load) of the holds whose readings of the gauge (``on``) mostly equal the extreme (``at``); a load is
    its axis, sign and mass."""
    out = []
    for s in np.unique(data.step[at]):
        hold = on & (data.step == s)
        if at[hold].mean() >= _HOLD_SHARE:
            out.append((int(s), _load(data, int(np.argmax(hold)))))
    return out


def _load(data: RigSamples, i: int) -> tuple:
    """The load of sample ``i``: its axis, sign and mass."""
    return int(data.axis[i]), float(data.sign[i]), round(float(data.mass[i]), 6)


def _others_scatter(data: RigSamples, on: np.ndarray, sigma: float, stopped: set) -> bool:
    """Whether the gauge's other loaded holds (mean at least :data:`RANGE_MIN_SD` SDs) scatter: at most a fifth of
    them read one value in :data:`_HOLD_SHARE` of their readings (with a resolution coarse against the noise every
    hold may read one value, and a frozen hold tells nothing)."""
    frozen, total = 0, 0
    for s in np.unique(data.step[on]):
        if int(s) in stopped:
            continue
        v = data.y[on & (data.step == s)]
        if v.size < 5 or abs(float(np.mean(v))) < RANGE_MIN_SD * sigma:
            continue
        total += 1
        frozen += np.unique(v, return_counts=True)[1].max() >= _HOLD_SHARE * v.size
    return total >= 3 and frozen <= 0.2 * total


def range_finding(data: RigSamples, limited: np.ndarray, rms_mm: float) -> list[Finding]:
    """One ``unexplained`` finding per gauge and end of its range whose readings ``limited`` sat at a stop: the
    value, how many readings and holds, that they were left out."""
    out = []
    for c, side in sorted({(int(c), float(np.sign(y))) for c, y in zip(data.comp[limited], data.y[limited]) if y}):
        at = limited & (data.comp == c) & (np.sign(data.y) == side)
        value = float(data.y[at][np.argmax(np.abs(data.y[at]))])
        holds = np.unique(data.step[at])
        loads = {_load(data, int(i)) for i in np.nonzero(at)[0]}
        why = ("of different loads (an elastic rod gives two loads two readings)" if len(loads) > 1 else
               "without the noise its other holds show")
        out.append(Finding(
            FindingKind.UNEXPLAINED, f"sensor:{_AXES[int(c)]}",
            f"the {_AXES[int(c)]} gauge read {value:.4f} mm in {int(at.sum())} readings over {holds.size} holds {why}: "
            "it sat at the end of its range; those readings were left out and the rest diagnosed without them: a "
            "property of the gauge's mounting, outside the effect vocabulary",
            {"range_limit_mm": value, "readings_left_out": int(at.sum())}, {}, rms_mm, rms_mm,
            {"outside_vocabulary": True, "holds": [int(h) for h in holds[:20]]}))
    return out
