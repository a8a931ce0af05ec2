"""The settling samples of an acquired recording: what `rig acquire` records before each hold proper.

`rodlab rig acquire` records every sample, also those read while a hold settles (the live readings must stay
within the plan's ``settle.tolerance_mm`` for ``settle.window_s``), and then the hold proper: ``hold_s`` x
``rate_Hz`` samples. The header's ``plan_fields`` states both, so the settling samples of each hold are the ones
before its last ``hold_s x rate_Hz``. A hung weight's settling (a swing, a lift lowering it) is no property of the
rod: fitted, it had read as a creep of phi 0.43 with a 0.5 s time constant, and the exported compliance had been
40 % too stiff (an instrument trial's own gauges, settling with a 0.15 s time constant).
"""
from __future__ import annotations

import dataclasses
import re
import warnings

import numpy as np

__all__ = ["missing_holds_text", "SettlingCut", "settled", "stated_hold_samples", "hold_part", "settling_seconds",
           "after_settling"]

#: a hold's level must move by more than this many reading-noise SDs for its settling to be looked at
STEP_NOISE = 10.0
#: the first reading of a settling hold is still this share of the step away from the hold's level, or more
SETTLING_START = 0.1
#: a settled reading is within this share of the step of its hold's level (the median over the holds)
SETTLED_SHARE = 0.02
#: a settling is over within this [s]; what goes on longer is a creep, for the diagnosis to name
SETTLING_MAX_S = 1.5
#: and stays over for at least this long after [s]
SETTLED_CHECK_S = 1.0
#: holds with a clear step needed to say a recording settles
MIN_HOLDS = 4
#: the cut goes on until the settling's tail is below this share of a reading's noise SD on the larger steps ...
TAIL_NOISE = 0.25
#: ... where the tail decays with a time constant below this [s] (a settling; a slower tail is the diagnosis's)
TAIL_TAU_MAX_S = 0.5
#: ... and at most this long [s]
SETTLING_CUT_MAX_S = 3.0

_FIELD = r"(?:^|\s){}=([0-9.eE+-]+)(?=\s|$)"


@dataclasses.dataclass(frozen=True)
class SettlingCut:
    """The recording without each hold's settling samples.

    recording : the hold proper of every hold; per_hold : the samples of a hold proper the header states
    (``hold_s x rate_Hz``), None where it states none; dropped : samples left out; holds : holds that had
    settling samples; incomplete : holds cut short (fewer samples than a settle window and a hold proper: an
    acquisition interrupted there and resumed under a new step), left out whole
    """

    recording: object
    per_hold: int | None
    dropped: int
    holds: int
    incomplete: int = 0
    seconds: float | None = None

    def to_dict(self) -> dict:
        """The report's ``settling`` entry (empty where nothing was left out)."""
        if not self.dropped:
            return {}
        how = {"hold_samples": self.per_hold} if self.per_hold is not None else {"seconds": self.seconds}
        return {"samples_left_out": self.dropped, "holds": self.holds, "incomplete_holds": self.incomplete, **how}

    def text(self) -> str:
        """What was left out, in a sentence ('' where nothing was)."""
        if not self.dropped:
            return ""
        if self.per_hold is not None:
            cut = (f"; {self.incomplete} hold(s) cut short (an acquisition interrupted there) left out "
                   "whole") if self.incomplete else ""
            return (f"the {self.dropped} samples `rig acquire` recorded while {self.holds} hold(s) settled are left out "
                    f"(each hold is its last {self.per_hold} samples, hold_s x rate_Hz of the header's plan_fields)"
                    + cut)
        return (f"each hold's first {self.seconds:.2g} s ({self.dropped} samples) left out: the readings approach each "
                "hold's level from the previous one's and have settled by then, as a hung weight settles (a swing, "
                "a lift still lowering it; a creep that fast would be cut too, and its deflection is in the settled "
                "level)")


def missing_holds_text(rec) -> str | None:
    """A sentence where an acquired recording holds fewer holds than its plan (``holds.count`` of the header's
    ``plan_fields``: an acquisition stopped early and not resumed), else None (an instrument trial: 20 of 26
    holds had been fitted without a word)."""
    m = re.search(_FIELD.format(re.escape("holds.count")), str(rec.meta.get("plan_fields") or ""))
    try:
        planned = int(float(m.group(1))) if m else 0
    except ValueError:
        return None
    present = int(np.unique(rec.step).size)
    if present >= planned:
        return None
    return (f"the recording holds {present} of its plan's {planned} holds (the acquisition stopped early): the fit "
            "is of those; `rig acquire` with the same plan and -o resumes it after the last complete hold")


def stated_hold_samples(meta: dict) -> int | None:
    """``hold_s x rate_Hz`` from an acquired recording's ``plan_fields`` header entry; None where it has none."""
    text = str(meta.get("plan_fields") or "")
    found = [re.search(_FIELD.format(re.escape(k)), text) for k in ("hold_s", "rate_Hz")]
    if not all(found):
        return None
    try:
        hold_s, rate = (float(m.group(1)) for m in found)
    except ValueError:
        return None
    n = int(round(hold_s * rate))
    return n if n >= 2 else None


def settled(rec) -> SettlingCut:
    """``rec`` without its settling: the samples before each hold proper where the header states it
    (:func:`hold_part`), else the readings of each hold's first seconds where the readings show a settling
    (:func:`settling_seconds`, :func:`after_settling`); ``rec`` itself where neither."""
    cut = hold_part(rec)
    if cut.per_hold is not None:
        return cut
    seconds = settling_seconds(rec)
    return cut if seconds is None else after_settling(rec, seconds)


def hold_part(rec) -> SettlingCut:
    """``rec`` (a :class:`~rodlab.stiffness_rig.RigRecording`) with the samples before each hold's last
    ``hold_s x rate_Hz`` left out, where its header states them; ``rec`` itself otherwise."""
    n = stated_hold_samples(rec.meta)
    if n is None:
        return SettlingCut(rec, None, 0, 0)
    keep = np.ones(rec.n, dtype=bool)
    holds = incomplete = 0
    for st in np.unique(rec.step):
        rows = np.flatnonzero(rec.step == st)
        rows = rows[np.argsort(rec.time_s[rows], kind="stable")]
        if rows.size > n:
            keep[rows[:-n]] = False
            holds += 1
        else:                            # a complete hold has a settle window (>= 2 samples) before its own
            keep[rows] = False
            incomplete += 1
    if keep.all():
        return SettlingCut(rec, n, 0, 0)
    return SettlingCut(rec.subset(keep), n, int((~keep).sum()), holds, incomplete)


def settling_seconds(rec) -> float | None:
    """How long each hold of ``rec`` settles [s], from its readings: pooled over the holds whose level moved by
    more than :data:`STEP_NOISE` noise SDs, a reading's distance to its hold's level as a share of the step from
    the previous hold's (the median over the holds at each reading of a hold) starts above
    :data:`SETTLING_START` and stays within :data:`SETTLED_SHARE` from some time under :data:`SETTLING_MAX_S`
    on; None where it does not (no settling, or a creep that goes on after it: time constants of seconds)."""
    span = SETTLING_MAX_S + SETTLED_CHECK_S
    shares = [c for c in _step_shares(rec) if c[0][-1, 0] >= span]   # a short or cut hold cannot show it: left out
    if len(shares) < MIN_HOLDS:
        return None
    curves = [c[0] for c in shares]
    n = min(len(c) for c in curves)
    with warnings.catch_warnings():                                  # a reading blank in every hold stays NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        u = np.nanmedian(np.array([c[:n] for c in curves]), axis=0)  # shape=(n, 2): time since the hold began, share
    t, share = u[:, 0], u[:, 1]
    if not np.isfinite(t).all():
        return None
    if not share[0] > SETTLING_START:
        return None
    within = t < span
    for k in range(1, int(np.sum(t < SETTLING_MAX_S))):
        later = share[k:][within[k:]]
        if np.all(np.abs(later[np.isfinite(later)]) < SETTLED_SHARE) and t[within].max() >= t[k] + SETTLED_CHECK_S:
            return _to_the_noise(t, share, float(t[k]), shares, _resolution_mm(rec))
    return None


def _resolution_mm(rec) -> float:
    """The gauges' resolution [mm] the header states (``resolution_mm``), else 0."""
    try:
        return max(float(rec.meta.get("resolution_mm") or 0.0), 0.0)
    except (TypeError, ValueError):
        return 0.0


def _to_the_noise(t: np.ndarray, share: np.ndarray, t_settled: float, shares: list, resolution_mm: float = 0.0
                  ) -> float:
    """The settling cut [s], past ``t_settled`` (within :data:`SETTLED_SHARE` of the step) until the tail is below
    :data:`TAIL_NOISE` of a reading's noise on the larger steps: 2 % of a 1 mm step is 20 um, and a soft rod's
    settling tail left in had read as a creep of 0.9 % at 28 standard errors (an instrument trial's own gauges,
    settling with 0.12-0.25 s). The tail's exponential is fitted to the median share curve where it stands above
    its own scatter; a tail slower than :data:`TAIL_TAU_MAX_S` is no weight's settling and is left to the
    diagnosis. A reading's noise is at least its quantisation (``resolution_mm`` / sqrt 12); the cut leaves at least
    two thirds of the median hold."""
    steps = np.array([c[1] for c in shares])
    noise = max(float(np.median([c[2] for c in shares])), resolution_mm / np.sqrt(12.0), 1e-6)
    big = float(np.quantile(steps, 0.9))
    floor = TAIL_NOISE * noise / big                                   # the share a settled tail stays below
    scatter = 1.25 * float(np.median(noise / steps)) / np.sqrt(len(shares))   # the median share's own scatter
    use = (t <= t_settled) & np.isfinite(share) & (share > max(5.0 * scatter, floor))
    if floor >= SETTLED_SHARE or use.sum() < 3:
        return t_settled
    slope, icpt = np.polyfit(t[use], np.log(share[use]), 1)
    if not slope < -1.0 / TAIL_TAU_MAX_S:
        return t_settled
    t_cut = (np.log(floor) - icpt) / slope
    hold = float(np.median([c[0][-1, 0] for c in shares]))
    return float(np.clip(t_cut, t_settled, max(t_settled, min(SETTLING_CUT_MAX_S, hold / 3.0))))


def _step_shares(rec) -> list[tuple[np.ndarray, float, float]]:
    """Per hold whose level moved clearly, per reading of its largest-moving gauge: (time since the hold's first
    reading [s], (reading - hold level) / (previous level - hold level)), shape=(m, 2); the level is the mean of
    the hold's later half; with the step's size [mm] and that gauge's scatter in the later half [mm]."""
    out = []
    prev, axis = None, None
    for st in _steps_in_order(rec):
        rows = np.flatnonzero(rec.step == st)
        rows = rows[np.argsort(rec.time_s[rows], kind="stable")]
        if rec.load_axis[rows[0]] is not axis:              # a new series: its gauges zeroed afresh
            prev, axis = None, rec.load_axis[rows[0]]
        late = rec.disp_mm[rows[rows.size // 2:]]
        with warnings.catch_warnings():                     # a gauge not read is NaN throughout
            warnings.simplefilter("ignore", RuntimeWarning)
            level, noise = np.nanmean(late, axis=0), np.nanstd(late, axis=0)
        if prev is not None and rows.size >= 6:
            jump = prev - level
            c = int(np.nanargmax(np.where(np.isfinite(jump), np.abs(jump), -1.0)))
            if np.isfinite(jump[c]) and abs(jump[c]) > STEP_NOISE * max(float(noise[c]), 1e-9):
                t = rec.time_s[rows] - rec.time_s[rows[0]]
                out.append((np.column_stack([t, (rec.disp_mm[rows, c] - level[c]) / jump[c]]), abs(float(jump[c])),
                            float(noise[c])))
        prev = level
    return out


def _steps_in_order(rec) -> list:
    """The recording's steps in the order of their first reading."""
    steps, first = np.unique(rec.step, return_index=True)
    return [int(s) for s in steps[np.argsort(rec.time_s[first], kind="stable")]]


def after_settling(rec, seconds: float) -> SettlingCut:
    """``rec`` without the readings of each hold's first ``seconds`` (after its first reading)."""
    keep = np.ones(rec.n, dtype=bool)
    holds = 0
    for st in np.unique(rec.step):
        rows = np.flatnonzero(rec.step == st)
        early = rows[rec.time_s[rows] - rec.time_s[rows].min() < seconds]
        if early.size and early.size < rows.size:
            keep[early] = False
            holds += 1
    return SettlingCut(rec.subset(keep), None, int((~keep).sum()), holds, seconds=seconds)
