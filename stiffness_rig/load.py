"""The measured load (a load cell's ``force_N``) against the hung mass: the rig's friction and tare, measured.

With a load cell between the loading frame and the rod, the fit uses the force the rod actually carries; the
difference ``mass_kg x g0 - force_N`` of each hold is what the rig took away on the way: Coulomb friction in
the slides (``+F_f`` while loading, ``-F_f`` while unloading) and a dead load missing from ``mass_kg``
(``-tare x g0`` on both branches whenever the hanger is on). Per load axis the two branch means give both::

    friction_N = (d_load - d_unload) / 2        tare_kg = -(d_load + d_unload) / (2 g0)

over the holds with a hanger on (mass > 0). The first hold of each load axis, without a hanger, carries no load (no friction
engaged yet): what the load cell reads there is its zero offset (``zero_offset_N``), taken off before friction and
tare (a 0.5 N offset had
been reported as a 51 g tare: new-user trial); the lines' slopes do not depend on it.

A load cell whose zero drifts during the recording (:func:`zero_drift`) shows as a trend in time of the
differences within each branch, where friction and tare are constant: its readings are then not the loads (a
drift of 1e-4 N/s had been reported as tares of 2-11 g and, by the diagnosis, as the gauges drifting: new-user
trial).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rodlab.core.enums import LoadAxis, Phase
from rodlab.core.units import G0

from .holds import Holds

__all__ = ["BranchLoad", "LoadCheck", "LoadScale", "ZeroDrift", "measured_load", "zero_drift", "load_scale",
           "DRIFT_Z"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class BranchLoad:
    """The difference nominal - measured load on one branch of one load axis.

    axis : the load axis; phase : load / unload; n_holds : holds with a hanger on (mass > 0);
    diff_N : mean of ``mass_kg x g0 - force_N`` over them [N]; sd_N : its scatter between holds [N]
    """

    axis: LoadAxis
    phase: Phase
    n_holds: int
    diff_N: float
    sd_N: float

    def to_dict(self) -> dict:
        return {"load_axis": str(self.axis), "phase": str(self.phase), "n_holds": self.n_holds,
                "diff_N": self.diff_N, "sd_N": self.sd_N}


#: a load cell's zero drift is reported when its rate lies this many standard errors from 0 ...
DRIFT_Z = 6.0
#: ... and it moves the zero by at least this much over the recording [N] (a load cell's resolution)
DRIFT_MIN_N = 0.005


@dataclass(frozen=True)
class ZeroDrift:
    """A load cell's zero moving linearly in time, from ``mass_kg x g0 - force_N`` of the holds with a hanger on.

    rate_N_per_s : the zero's rate [N/s] (the reading grows by it: the differences fall); se_N_per_s : its
    standard error; span_N : the zero's move over the holds' time span [N]; holds : holds used
    """

    rate_N_per_s: float
    se_N_per_s: float
    span_N: float
    holds: int

    @property
    def found(self) -> bool:
        """The drift stands out: :data:`DRIFT_Z` standard errors and at least :data:`DRIFT_MIN_N` over the run."""
        return (np.isfinite(self.se_N_per_s) and abs(self.rate_N_per_s) >= DRIFT_Z * self.se_N_per_s
                and abs(self.span_N) >= DRIFT_MIN_N)

    def to_dict(self) -> dict:
        return {"rate_N_per_s": self.rate_N_per_s, "se_N_per_s": self.se_N_per_s, "span_N": self.span_N,
                "holds": self.holds, "found": bool(self.found)}


def zero_drift(t_s: np.ndarray, diff_N: np.ndarray, branch: np.ndarray) -> ZeroDrift | None:
    """The common time trend of ``diff_N`` (``mass x g0 - load-cell reading`` per hold with a hanger on [N], at
    the holds' times ``t_s`` [s]) with one level per ``branch`` label (friction and tare are constant on a branch;
    shape=(m,) each): least squares, its standard error from the scatter about the fit. None with too few holds."""
    t_s, diff_N = np.asarray(t_s, float), np.asarray(diff_N, float)
    labels, idx = np.unique(np.asarray(branch), return_inverse=True)
    ok = np.isfinite(diff_N) & np.isfinite(t_s)
    dof = int(ok.sum()) - labels.size - 1
    if dof < 3 or np.ptp(t_s[ok]) <= 0:
        return None
    slope, se = _slope_with_levels(t_s[ok], diff_N[ok], idx[ok], labels.size)
    return ZeroDrift(-slope, se, -slope * float(np.ptp(t_s[ok])), int(ok.sum()))


def _slope_with_levels(x: np.ndarray, y: np.ndarray, level: np.ndarray, n_levels: int) -> tuple[float, float]:
    """(slope, its standard error) of ``y`` on ``x`` with one level per group (``level``: 0 .. n_levels - 1 per
    point): least squares, the error from the scatter about the fit (needs more points than n_levels + 1)."""
    X = np.column_stack([x, np.eye(n_levels)[level]])
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = y - X @ coef
    cov = np.linalg.pinv(X.T @ X) * float(r @ r) / (X.shape[0] - X.shape[1])
    return float(coef[0]), float(np.sqrt(max(cov[0, 0], 0.0)))


@dataclass(frozen=True)
class LoadScale:
    """How fast the load cell's reading grows with the hung weight: the slope of ``force_N`` on ``mass_kg x g0``
    over the holds with a hanger on, one intercept per branch (friction and tare are constant on a branch).

    axis : the load axis of the holds; ratio : the slope [-] (1 for a load cell that reads newtons of the weights;
    0.102 for one reading kgf, 0.225 lbf, 0 for one out of that axis's load path); se : its standard error [-]
    (NaN where the holds leave no scatter to estimate it: a short plan);
    n_holds : the holds it is fitted on
    """

    axis: LoadAxis
    ratio: float
    se: float
    n_holds: int

    def to_dict(self) -> dict:
        return {"axis": self.axis.value, "ratio": self.ratio, "se": self.se, "n_holds": self.n_holds}


@dataclass(frozen=True)
class LoadCheck:
    """Nominal (mass x g0) against measured load (a load cell).

    per_hold_N : shape=(m,) ``mass_kg x g0 - force_N`` of every hold [N] (hold order of the fit's holds);
    branches : one :class:`BranchLoad` per (axis, phase); friction_N, tare_kg : {load axis: value} from the
    branch means ([N], [kg]); force_noise_N : within-hold SD of one load-cell reading [N];
    zero_offset_N : the load cell's mean reading on the holds without a hanger [N], taken off the others (0 when it
    is within noise of 0 or no hold is without a hanger); drift : :class:`ZeroDrift` of its zero (None: too few
    holds); scale : one :class:`LoadScale` per load axis where it can be fitted
    """

    per_hold_N: np.ndarray
    branches: tuple
    friction_N: dict
    tare_kg: dict
    force_noise_N: float
    zero_offset_N: float = 0.0
    drift: ZeroDrift | None = None
    scale: tuple[LoadScale, ...] = ()

    def to_dict(self) -> dict:
        return {"per_hold_N": [float(v) for v in self.per_hold_N], "branches": [b.to_dict() for b in self.branches],
                "friction_N": {str(a): v for a, v in self.friction_N.items()},
                "tare_kg": {str(a): v for a, v in self.tare_kg.items()}, "force_noise_N": self.force_noise_N,
                "zero_offset_N": self.zero_offset_N, "zero_drift": self.drift.to_dict() if self.drift else None,
                "scale": [sc.to_dict() for sc in self.scale]}


def measured_load(holds: Holds) -> LoadCheck | None:
    """Compare every hold's load-cell mean with its ``mass_kg x g0``; None without a load cell on every hold."""
    if not holds.has_force:
        some = int(np.isfinite(holds.force_N).sum())
        if some:
            log.warning("the load cell read on %d of %d holds only; the fit uses mass_kg x g0 on every hold",
                        some, len(holds))
        return None
    zero = zero_offset(holds)
    diff = holds.mass_kg * G0 - (holds.force_N - zero)
    branches, friction, tare = [], {}, {}
    for axis in sorted(set(holds.axis), key=lambda a: a.value):
        means = {}
        for phase in (Phase.LOAD, Phase.UNLOAD):
            m = np.array([a is axis and p is phase for a, p in zip(holds.axis, holds.phase)]) & (holds.mass_kg > 0)
            if m.any():
                d = diff[m]
                branches.append(BranchLoad(axis, phase, int(m.sum()), float(d.mean()),
                                           float(d.std(ddof=1)) if d.size > 1 else float("nan")))
                means[phase] = float(d.mean())
        if len(means) == 2:
            friction[axis] = 0.5 * (means[Phase.LOAD] - means[Phase.UNLOAD])
            tare[axis] = -0.5 * (means[Phase.LOAD] + means[Phase.UNLOAD]) / G0
        elif means:
            tare[axis] = -next(iter(means.values())) / G0
    on = holds.mass_kg > 0
    mid = 0.5 * (holds.t_start_s + holds.t_end_s)
    branch = np.array([f"{a.value}:{p.value}" for a, p in zip(holds.axis, holds.phase)])
    drift = zero_drift(mid[on], diff[on], branch[on])
    scale = []
    for axis in sorted(set(holds.axis), key=lambda a: a.value):
        m = on & np.array([a is axis for a in holds.axis])
        sc = load_scale(axis, holds.mass_kg[m] * G0, holds.force_N[m], branch[m])
        scale += [sc] if sc is not None else []
    return LoadCheck(diff, tuple(branches), friction, tare, holds.force_noise_N(), zero, drift, tuple(scale))


def load_scale(axis: LoadAxis, weight_N: np.ndarray, force_N: np.ndarray, branch: np.ndarray) -> LoadScale | None:
    """The slope of ``force_N`` on ``weight_N`` (:class:`LoadScale`) with one intercept per ``branch`` label, over
    the holds of load axis ``axis`` given (shape=(m,) each); None when no branch has two different weights or nothing
    is left for the residuals."""
    labels, idx = np.unique(np.asarray(branch), return_inverse=True)
    if not any(np.ptp(weight_N[idx == k]) > 0 for k in range(labels.size)):
        return None
    if weight_N.size - labels.size - 1 < 1:          # a short plan: the slope without a scatter to judge it by
        X = np.column_stack([weight_N, np.eye(labels.size)[idx]])
        coef = np.linalg.lstsq(X, force_N, rcond=None)[0]
        return LoadScale(axis, float(coef[0]), float("nan"), int(weight_N.size))
    ratio, se = _slope_with_levels(weight_N, force_N, idx, labels.size)
    return LoadScale(axis, ratio, se, int(weight_N.size))


def zero_offset(holds: Holds) -> float:
    """The load cell's mean reading on the first hold of each load axis when it is without a hanger [N] (the
    series' zero reference: no hanger, no friction engaged yet; later holds at mass 0 may keep the slides'
    friction) where it differs from 0 by more than 5 standard errors; else 0."""
    first = {}
    for i, a in enumerate(holds.axis):
        first.setdefault(a, i)
    idx = [i for i in first.values() if holds.mass_kg[i] == 0.0 and np.isfinite(holds.force_N[i])]
    if not idx:
        return 0.0
    f = holds.force_N[idx]
    within = holds.force_noise_N() / np.sqrt(max(float(np.median(holds.n[idx])), 1.0))
    between = float(f.std(ddof=1)) if f.size > 1 else 0.0
    se = max(np.hypot(within, between) / np.sqrt(f.size), 1e-6)
    return float(f.mean()) if abs(f.mean()) > 5 * se else 0.0
