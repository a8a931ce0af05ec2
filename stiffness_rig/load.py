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
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rodlab.core.enums import LoadAxis, Phase
from rodlab.core.units import G0

from .holds import Holds

__all__ = ["BranchLoad", "LoadCheck", "measured_load"]

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


@dataclass(frozen=True)
class LoadCheck:
    """Nominal (mass x g0) against measured load (a load cell).

    per_hold_N : shape=(m,) ``mass_kg x g0 - force_N`` of every hold [N] (hold order of the fit's holds);
    branches : one :class:`BranchLoad` per (axis, phase); friction_N, tare_kg : {load axis: value} from the
    branch means ([N], [kg]); force_noise_N : within-hold SD of one load-cell reading [N];
    zero_offset_N : the load cell's mean reading on the holds without a hanger [N], taken off the others (0 when it
    is within noise of 0 or no hold is without a hanger)
    """

    per_hold_N: np.ndarray
    branches: tuple
    friction_N: dict
    tare_kg: dict
    force_noise_N: float
    zero_offset_N: float = 0.0

    def to_dict(self) -> dict:
        return {"per_hold_N": [float(v) for v in self.per_hold_N], "branches": [b.to_dict() for b in self.branches],
                "friction_N": {str(a): v for a, v in self.friction_N.items()},
                "tare_kg": {str(a): v for a, v in self.tare_kg.items()}, "force_noise_N": self.force_noise_N,
                "zero_offset_N": self.zero_offset_N}


def measured_load(holds: Holds) -> LoadCheck | None:
    """Compare every hold's load-cell mean with its ``mass_kg x g0``; None without a load cell on every hold."""
    if not holds.has_force:
        some = int(np.isfinite(holds.force_N).sum())
        if some:
            log.warning("the load cell read on %d of %d holds only; the fit uses mass_kg x g0 on every hold",
                        some, len(holds))
        return None
    zero = _zero_offset(holds)
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
    return LoadCheck(diff, tuple(branches), friction, tare, holds.force_noise_N(), zero)


def _zero_offset(holds: Holds) -> float:
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
