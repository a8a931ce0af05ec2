"""Constant-load holds of a recording: averages over the settled part, within-hold noise."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.units import G0


from .recording import RigRecording

__all__ = ["Holds", "hold_averages", "SETTLE_FRACTION"]

#: fraction of each hold discarded at its start (the hanger swinging out, sensor settling)
SETTLE_FRACTION = 0.3


@dataclass
class Holds:
    """One row per hold (step).

    step, repeat : shape=(m,) int; phase, axis : shape=(m,) of Phase / LoadAxis; mass_kg : shape=(m,) [kg]
    t_start_s, t_end_s : first and last sample time [s]; mean_mm, std_mm : shape=(m, 3) over the settled
    samples [mm] (NaN where not measured); n : settled samples; temp_C : mean temperature or NaN;
    slope_mm_per_s : shape=(m, 3), linear trend within the settled part (creep / drift).
    force_N, force_std_N : shape=(m,) mean and SD of the load cell's settled readings along the load axis [N]
    (NaN without a load cell).
    """

    step: np.ndarray
    repeat: np.ndarray
    phase: np.ndarray
    axis: np.ndarray
    mass_kg: np.ndarray
    t_start_s: np.ndarray
    t_end_s: np.ndarray
    mean_mm: np.ndarray
    std_mm: np.ndarray
    n: np.ndarray
    temp_C: np.ndarray
    slope_mm_per_s: np.ndarray
    force_N: np.ndarray = None
    force_std_N: np.ndarray = None

    def __post_init__(self) -> None:
        for name in ("force_N", "force_std_N"):
            if getattr(self, name) is None:
                setattr(self, name, np.full(self.step.shape, np.nan))

    @property
    def has_force(self) -> bool:
        """Every hold has a measured load (a load cell's mean)."""
        return len(self) > 0 and bool(np.isfinite(self.force_N).all())

    def load_N(self, axis_sign=None) -> np.ndarray:
        """The load of each hold along its axis [N]: the load cell's mean when every hold has one, else
        mass_kg x g0; times ``axis_sign`` (shape=(m,)) when given."""
        F = self.force_N if self.has_force else self.mass_kg * G0
        return F if axis_sign is None else F * axis_sign

    def force_noise_N(self) -> float:
        """Pooled within-hold SD of one load-cell reading [N] (NaN without a load cell)."""
        ok = np.isfinite(self.force_std_N) & (self.n > 1)
        dof = (self.n[ok] - 1).sum()
        return float(np.sqrt((self.force_std_N[ok] ** 2 * (self.n[ok] - 1)).sum() / dof)) if dof > 0 else float("nan")

    def __len__(self) -> int:
        return int(self.step.size)

    def select(self, mask) -> "Holds":
        return Holds(**{k: getattr(self, k)[mask] for k in self.__dataclass_fields__})

    def noise_mm(self) -> float:
        """Pooled within-hold standard deviation of a reading [mm] (never from a model fit)."""
        v = self.std_mm ** 2 * (self.n[:, None] - 1)
        ok = np.isfinite(v)
        dof = ((self.n[:, None] - 1) * ok).sum()
        return float(np.sqrt(np.nansum(v) / dof)) if dof > 0 else float("nan")


def hold_averages(rec: RigRecording, settle_fraction: float = SETTLE_FRACTION) -> Holds:
    """Average every hold over its settled part (the last ``1 - settle_fraction`` of its samples)."""
    rows = []
    order = np.argsort(rec.step, kind="stable")
    step_sorted = rec.step[order]
    bounds = np.flatnonzero(np.diff(step_sorted)) + 1
    groups = np.split(order, bounds)
    first_time = {int(rec.step[g[0]]): rec.time_s[g].min() for g in groups}
    groups.sort(key=lambda g: first_time[int(rec.step[g[0]])])
    for g in groups:
        g = g[np.argsort(rec.time_s[g], kind="stable")]
        k0 = int(np.floor(settle_fraction * g.size))
        s = g[k0:] if g.size - k0 >= 2 else g
        t = rec.time_s[s]
        d = rec.disp_mm[s]
        fin = np.isfinite(d)
        cnt = fin.sum(axis=0)
        dz = np.where(fin, d, 0.0)
        mean = np.where(cnt > 0, dz.sum(axis=0) / np.maximum(cnt, 1), np.nan)
        dev = np.where(fin, d - mean, 0.0)
        std = np.where(cnt > 1, np.sqrt((dev ** 2).sum(axis=0) / np.maximum(cnt - 1, 1)), np.nan)
        slope = np.full(3, np.nan)
        for c in range(3):                       # a reading or two left out as glitches keep the hold's trend
            m = fin[:, c]
            if m.sum() >= max(3, s.size - 2) and np.ptp(t[m]) > 0:
                tc = t[m] - t[m].mean()
                slope[c] = float(tc @ (d[m, c] - d[m, c].mean()) / (tc @ tc))
        temp = float(np.nanmean(rec.temp_C[s])) if rec.temp_C is not None and np.isfinite(rec.temp_C[s]).any() \
            else np.nan
        i0 = g[0]
        rows.append((rec.step[i0], rec.repeat[i0], rec.phase[i0], rec.load_axis[i0], rec.mass_kg[i0],
                     rec.time_s[g].min(), rec.time_s[g].max(), mean, std, s.size, temp, slope)
                    + _force_stats(rec, s))
    col = lambda j, dt=float: np.array([r[j] for r in rows], dtype=dt)  # noqa: E731
    return Holds(col(0, int), col(1, int), np.array([r[2] for r in rows], dtype=object),
                 np.array([r[3] for r in rows], dtype=object), col(4), col(5), col(6),
                 np.array([r[7] for r in rows]), np.array([r[8] for r in rows]), col(9, int), col(10),
                 np.array([r[11] for r in rows]), col(12), col(13))


def _force_stats(rec: RigRecording, s: np.ndarray) -> tuple[float, float]:
    """(mean, SD) of the load cell's readings among the samples ``s`` [N]; NaN without any."""
    if rec.force_N is None:
        return np.nan, np.nan
    f = rec.force_N[s]
    f = f[np.isfinite(f)]
    if f.size == 0:
        return np.nan, np.nan
    return float(f.mean()), float(f.std(ddof=1)) if f.size > 1 else np.nan
