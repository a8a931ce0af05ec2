"""A recording flattened to one row per measured reading: what rig effects' hypotheses are built on."""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from rodlab.core.enums import Phase
from rodlab.core.units import G0

__all__ = ["RigSamples", "rig_samples"]


@dataclass
class RigSamples:
    """Every measured reading of a recording, flattened over the measured components.

    y : reading [mm]; comp : gauge component 0..2 (x, y, z of {T}); axis : load axis index 0..2; sign : +1 / -1
    of the load axis; F : signed load along the axis [N]: the hold's mean load-cell reading when the recording has
    ``force_N`` on every hold, else mass x g0; mass : hung mass [kg]; unload : on an
    unloading branch; reference : the series-start reading the gauges were zeroed on (mass 0, first step);
    t_hold : time since the hold started [s]; t_series : time since the series (load axis) started [s];
    temp : temperature relative to the series start [K] (NaN without ``temp_C``); step, repeat : hold index and
    repeat; t_abs : recording time [s]; F_se : standard error of the hold's mean load [N] (the load cell's
    noise over its readings in the hold; 0 for mass x g0); series : the series the reading belongs to (one per
    run of one load axis and sign, in recording order: an axis loaded again later is a new series; None: from
    ``axis`` and ``sign``). All shape=(n,).
    """

    y: np.ndarray
    comp: np.ndarray
    axis: np.ndarray
    sign: np.ndarray
    F: np.ndarray
    mass: np.ndarray
    unload: np.ndarray
    reference: np.ndarray
    t_hold: np.ndarray
    t_series: np.ndarray
    temp: np.ndarray
    step: np.ndarray
    repeat: np.ndarray
    t_abs: np.ndarray
    F_se: np.ndarray | None = None
    series: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = np.shape(self.y)
        if self.F_se is None:
            self.F_se = np.zeros(n)
        if self.series is None:
            self.series = 2 * np.asarray(self.axis, dtype=int) + (np.asarray(self.sign) > 0)
        for f in fields(self):
            if np.shape(getattr(self, f.name)) != n:
                raise ValueError(f"RigSamples.{f.name} must have the shape of y {n}, got "
                                 f"{np.shape(getattr(self, f.name))}")

    @property
    def n(self) -> int:
        return int(self.y.size)

    @property
    def zero_groups(self) -> np.ndarray:
        """shape=(n,) one integer per gauge and series: the readings that share a gauge zero (the gauges are zeroed
        at every series' start, so the x and -x series of one gauge have a zero each)."""
        return np.asarray(self.series, dtype=int) * 4 + self.comp

    def subset(self, keep: np.ndarray) -> "RigSamples":
        """The rows where ``keep`` is true."""
        return RigSamples(*[getattr(self, f.name)[keep] for f in fields(self)])


def rig_samples(rec, hold_start: dict | None = None) -> RigSamples:
    """Flatten a :class:`~rodlab.stiffness_rig.RigRecording` into one row per measured reading (component by
    component, readings in recording order). ``hold_start``: {step: time of the hold's first recorded reading [s]}
    where readings were left out before (a settling), for ``t_hold``; default each step's first reading here."""
    la = list(rec.load_axis)
    code = rec.series()
    axes = [la[i] for i in np.unique(code, return_index=True)[1]]   # each series' load axis
    step = np.asarray(rec.step)
    idx = np.concatenate([np.nonzero(np.isfinite(rec.disp_mm[:, c]))[0] for c in range(3)])
    first = _first_rows(code)[idx]                                  # the first row of each reading's series
    first_of_step = _first_rows(step)[idx]                          # and of its hold
    temp = np.asarray(rec.temp_C, dtype=float) if rec.temp_C is not None else np.full(rec.n, np.nan)
    load, load_se = _hold_loads_N(rec)
    comp = np.concatenate([np.full(int(np.isfinite(rec.disp_mm[:, c]).sum()), c) for c in range(3)])
    ax_index = np.array([a.index for a in axes], dtype=int)[code[idx]]
    ax_sign = np.array([a.sign for a in axes], dtype=float)[code[idx]]
    t = np.asarray(rec.time_s, dtype=float)
    st = step[idx]
    return RigSamples(
        y=rec.disp_mm[idx, comp], comp=comp, axis=ax_index, sign=ax_sign,
        F=np.array([load[k] for k in st.tolist()]) * ax_sign, mass=np.asarray(rec.mass_kg, dtype=float)[idx],
        unload=np.array([p is Phase.UNLOAD for p in rec.phase], dtype=bool)[idx],
        reference=(st == step[first]) & (np.asarray(rec.mass_kg)[idx] == 0),
        t_hold=t[idx] - _starts(t, step, first_of_step, idx, hold_start), t_series=t[idx] - t[first],
        temp=temp[idx] - temp[first],
        step=st.astype(int), repeat=np.asarray(rec.repeat, dtype=int)[idx], t_abs=t[idx],
        F_se=np.array([load_se[k] for k in st.tolist()]), series=code[idx])


def _starts(t: np.ndarray, step: np.ndarray, first_of_step: np.ndarray, idx: np.ndarray, hold_start) -> np.ndarray:
    """Each reading's hold start [s]: ``hold_start`` of its step where given (no later than its first reading
    here), else its step's first reading here."""
    here = t[first_of_step]
    if not hold_start:
        return here
    given = np.array([hold_start.get(int(k), np.inf) for k in step[idx].tolist()], float)
    return np.minimum(here, given)


def _first_rows(keys: np.ndarray) -> np.ndarray:
    """For every row, the first row with the same value of ``keys`` (integers)."""
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    return first[inverse]


def _hold_loads_N(rec) -> tuple[dict, dict]:
    """({step: load along the axis [N]}, {step: its standard error [N]}): every hold's mean load-cell reading
    when each hold has one, else mass_kg x g0 with no error (a load cell missing on some holds is not mixed with
    nominal loads)."""
    nominal = {int(st): float(m) * G0 for st, m in zip(rec.step, rec.mass_kg)}
    exact = dict.fromkeys(nominal, 0.0)
    if not getattr(rec, "has_force", False):
        return nominal, exact
    measured, se = {}, {}
    for st in nominal:
        f = rec.force_N[rec.step == st]
        f = f[np.isfinite(f)]
        if f.size == 0:
            return nominal, exact
        measured[st] = float(f.mean())
        se[st] = float(f.std(ddof=1) / np.sqrt(f.size)) if f.size > 1 else 0.0
    return measured, se
