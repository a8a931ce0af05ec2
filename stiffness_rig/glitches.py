"""Single readings far off their hold's line: a gauge's glitch or an electrical spike, not the rod or the rig.

One 0.5 mm reading among 10 000 had made a diagnosis's noise 5 um instead of 0.66 um and hidden a joint; one cut-off
59 um reading (an instrument trial's gauge answering "+0007.8") had made `rig fit`'s noise 1.46 um instead of 0.5 um
and one entry's standard error 10x the others', without a word. Both the diagnosis and `rig fit` leave them out
and say where (:func:`isolated_glitches` on a recording's readings, :func:`glitch_rows` on the recording).
"""
from __future__ import annotations

import numpy as np

from .samples import RigSamples, rig_samples

__all__ = ["isolated_glitches", "glitch_rows", "without_glitches", "hold_line_residuals", "reading_quantum", "GLITCH_Z",
           "GLITCH_SHARE_MAX"]

#: a reading this many robust SDs off its hold's line is a glitch (Gaussian noise: never, p ~ 1e-23) ...
GLITCH_Z = 10.0
#: ... when such readings are this rare (more are physics, or a noisier gauge, not glitches)
GLITCH_SHARE_MAX = 0.005


def isolated_glitches(data: RigSamples) -> np.ndarray:
    """The readings (bool, shape=(n,)) that are glitches: in a pass over every (hold, gauge), its one reading
    farthest off the line through the others (a leave-one-out residual: a spike cannot pull its own line), when
    that is more than :data:`GLITCH_Z` robust SDs and 5 gauge steps off; two passes (at most two per hold). Kept
    only when rare (at most :data:`GLITCH_SHARE_MAX` of the readings), not at one place in the holds (a
    reading off in many holds at the same moment is settling or handling, not a glitch) and not where the hold's
    level jumps (:func:`_at_a_jump`: a gauge slipping within a hold leaves its two readings next to the jump off
    the line, which a review had found called two glitches)."""
    none = np.zeros(data.n, dtype=bool)
    resid, dof = hold_line_residuals(data)
    fitted = np.isfinite(resid)
    if fitted.sum() < 20 or dof < 1:
        return none
    # robust SD of one reading: the residuals' MAD, corrected for the lines' fitted parameters
    robust = 1.4826 * float(np.median(np.abs(resid[fitted]))) * np.sqrt(fitted.sum() / dof)
    limit = max(GLITCH_Z * robust, 5.0 * reading_quantum(data.y))
    if not limit > 0:
        return none
    flagged = none.copy()
    for _ in range(2):
        worst = _worst_left_out(data, flagged, limit)
        if not worst.any():
            break
        flagged |= worst
    flagged &= ~_at_a_jump(data, flagged, limit)
    if not flagged.any() or flagged.sum() > GLITCH_SHARE_MAX * data.n or _at_one_place(data, flagged):
        return none
    return flagged


def _worst_left_out(data: RigSamples, skip: np.ndarray, limit: float) -> np.ndarray:
    """In each (hold, gauge) with >= 3 readings not in ``skip``, its reading farthest off the line through the
    others, where that is beyond ``limit`` [mm]."""
    out = np.zeros(data.n, dtype=bool)
    keys = data.step * 4 + data.comp
    for k in np.unique(keys):
        u = np.nonzero((keys == k) & ~skip)[0]
        if u.size < 3:
            continue
        t = data.t_hold[u] - data.t_hold[u].mean()
        sxx = float(t @ t)
        A = np.column_stack([np.ones_like(t), t])
        coef, *_ = np.linalg.lstsq(A, data.y[u], rcond=None)
        h = 1.0 / u.size + (t * t / sxx if sxx > 0 else 0.0)
        loo = (data.y[u] - A @ coef) / np.maximum(1.0 - h, 1e-9)
        i = int(np.argmax(np.abs(loo)))
        if abs(loo[i]) > limit:
            out[u[i]] = True
    return out


#: readings on each side of a flagged one whose median is its hold's level there
_SIDE = 5


def _at_a_jump(data: RigSamples, flagged: np.ndarray, limit: float) -> np.ndarray:
    """The flagged readings across which their (hold, gauge)'s level changes by more than half ``limit``: the
    median of up to :data:`_SIDE` unflagged readings before against as many after. A spike leaves both sides
    alike; a slip does not."""
    out = np.zeros(data.n, dtype=bool)
    keys = data.step * 4 + data.comp
    for i in np.flatnonzero(flagged):
        u = np.flatnonzero((keys == keys[i]) & ~flagged)
        t = data.t_hold[u]
        before, after = data.y[u[t < data.t_hold[i]]][-_SIDE:], data.y[u[t > data.t_hold[i]]][:_SIDE]
        if before.size and after.size and abs(float(np.median(after) - np.median(before))) > 0.5 * limit:
            out[i] = True
    return out


def _at_one_place(data: RigSamples, flagged: np.ndarray) -> bool:
    """Whether the flagged readings sit mostly at one place in their holds (the same reading of each hold)."""
    if flagged.sum() < 3:
        return False
    keys = data.step * 4 + data.comp
    order = np.lexsort((data.t_hold, keys))
    index = np.empty(data.n, dtype=int)
    _, start = np.unique(keys[order], return_index=True)
    counts = np.diff(np.append(start, data.n))
    index[order] = np.arange(data.n) - np.repeat(start, counts)    # the reading's place in its hold
    return np.bincount(index[flagged]).max() > 0.5 * flagged.sum()


def hold_line_residuals(data: RigSamples, skip: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """Each reading's residual from a line in time through its (hold, gauge) (NaN in (hold, gauge)s of fewer than
    3 readings), the line fitted without the readings ``skip``; and the lines' degrees of freedom."""
    resid = np.full(data.n, np.nan)
    dof = 0
    keys = data.step * 4 + data.comp
    use = np.ones(data.n, dtype=bool) if skip is None else ~skip
    for k in np.unique(keys):
        m = np.nonzero(keys == k)[0]
        u = m[use[m]]
        if u.size < 3:
            continue
        t, y = data.t_hold[u], data.y[u]
        tm = t.mean()
        A = np.column_stack([np.ones_like(t), t - tm])
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        resid[m] = data.y[m] - coef[0] - coef[1] * (data.t_hold[m] - tm)
        dof += u.size - 2
    return resid, dof


def reading_quantum(y: np.ndarray) -> float:
    """The gauges' reading step [mm] when the readings lie on a grid (0 when they do not)."""
    u = np.unique(np.round(np.asarray(y, float), 9))
    steps = np.diff(u)
    steps = steps[steps > 1e-9]
    if steps.size == 0:
        return 0.0
    q = float(steps.min())
    k = u / q
    return q if np.mean(np.abs(k - np.round(k)) < 0.02) > 0.99 else 0.0


def glitch_rows(rec) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(recording rows, gauge components 0-2, how far each is off its hold's line through the others [mm]) of the
    readings of ``rec`` (a :class:`~rodlab.stiffness_rig.RigRecording`) that :func:`isolated_glitches` finds."""
    data = rig_samples(rec)
    flagged = isolated_glitches(data)
    rows = np.concatenate([np.nonzero(np.isfinite(rec.disp_mm[:, c]))[0] for c in range(3)])
    comps = np.concatenate([np.full(int(np.isfinite(rec.disp_mm[:, c]).sum()), c) for c in range(3)])
    off = hold_line_residuals(data, flagged)[0][flagged] if flagged.any() else np.zeros(0)
    return rows[flagged], comps[flagged], off


def without_glitches(rec):
    """(``rec`` with its glitches (:func:`glitch_rows`) blanked, [a warning naming their holds]) for `rig fit`."""
    rows, comps, off = glitch_rows(rec)
    if rows.size == 0:
        return rec, []
    steps = sorted({int(s) for s in rec.step[rows]})
    return rec.without_readings(rows, comps), [
        f"{rows.size} single reading(s) far off their hold's line (step {', '.join(map(str, steps[:12]))}"
        f"{', ...' if len(steps) > 12 else ''}; up to {np.max(np.abs(off)) * 1e3:.1f} um, more than {GLITCH_Z:g} "
        "robust noise SDs): a gauge's glitch or an electrical spike, left out of the fit; check that gauge's cable "
        "and protocol if they recur"]
