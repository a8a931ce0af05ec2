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
    noise over its readings in the hold; 0 for mass x g0). All shape=(n,).
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

    def __post_init__(self) -> None:
        n = np.shape(self.y)
        if self.F_se is None:
            self.F_se = np.zeros(n)
        for f in fields(self):
            if np.shape(getattr(self, f.name)) != n:
                raise ValueError(f"RigSamples.{f.name} must have the shape of y {n}, got "
                                 f"{np.shape(getattr(self, f.name))}")

    @property
    def n(self) -> int:
        return int(self.y.size)

    def subset(self, keep: np.ndarray) -> "RigSamples":
        """The rows where ``keep`` is true."""
        return RigSamples(*[getattr(self, f.name)[keep] for f in fields(self)])


def rig_samples(rec) -> RigSamples:
    """Flatten a :class:`~rodlab.stiffness_rig.RigRecording` into one row per measured reading."""
    series_start, series_temp, hold_start, first_step = {}, {}, {}, {}
    for i in range(rec.n):
        ax = rec.load_axis[i]
        if ax not in series_start:
            series_start[ax] = rec.time_s[i]
            series_temp[ax] = rec.temp_C[i] if rec.temp_C is not None else np.nan
            first_step[ax] = rec.step[i]
        hold_start.setdefault(rec.step[i], rec.time_s[i])
    load, load_se = _hold_loads_N(rec)
    rows = []
    for c in range(3):
        for i in np.nonzero(np.isfinite(rec.disp_mm[:, c]))[0]:
            ax = rec.load_axis[i]
            rows.append((rec.disp_mm[i, c], c, ax.index, ax.sign, load[rec.step[i]] * ax.sign, rec.mass_kg[i],
                         rec.phase[i] is Phase.UNLOAD, rec.step[i] == first_step[ax] and rec.mass_kg[i] == 0,
                         rec.time_s[i] - hold_start[rec.step[i]], rec.time_s[i] - series_start[ax],
                         (rec.temp_C[i] - series_temp[ax]) if rec.temp_C is not None else np.nan, rec.step[i],
                         rec.repeat[i], rec.time_s[i], load_se[rec.step[i]]))
    a = list(zip(*rows))
    return RigSamples(np.array(a[0]), np.array(a[1], int), np.array(a[2], int), np.array(a[3], float),
                      np.array(a[4]), np.array(a[5]), np.array(a[6], bool), np.array(a[7], bool), np.array(a[8]),
                      np.array(a[9]), np.array(a[10], float), np.array(a[11], int), np.array(a[12], int),
                      np.array(a[13]), np.array(a[14]))


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
