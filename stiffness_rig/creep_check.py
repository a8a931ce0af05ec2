"""Creep seen within the holds of a recording, for `rig fit`'s warning.

A rod that creeps keeps deflecting after each change of load: its hold means, and so the lines' slopes `rig fit`
takes, include part of the creep, by how long each hold lasts (an instrument trial: a laminate creeping 4 % with a
4 s time constant gave a compliance 3.4 % soft from holds of 4 s). The check fits the on-axis gauges' readings
within their holds (each hold's mean taken out, and a drift within the holds per axis), every load axis together,
each weighted by its own scatter, to one Kelvin-Voigt creep of the load history
(:func:`~stiffness_rig.effects.creep.kelvin_voigt`'s recursion, relative to each axis's elastic deflection: the
laminate's creep is one share of it on every axis) for each time constant of
:data:`~stiffness_rig.effects.creep.CREEP_TAU_GRID_S`; a creep is said where the best one stands :data:`CREEP_Z`
standard errors out. The shape it looks for (a rise after
a load step up, a fall after one down, fading over seconds) is what settling left in or a drift are not: the
settling is out before (:mod:`.settling`), and a drift moves every hold the same way.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.units import G0

from .effects.creep import CREEP_TAU_GRID_S, relax
from .recording import RigRecording

__all__ = ["CreepCheck", "creep_within_holds", "CREEP_Z"]

#: standard errors the best creep's amplitude must stand out (13 time constants tried on each load axis): an
#: independent simulator's 45 recordings without creep reach 2.8 at most, its creeping ones (2-4 %, 5-15 s) 4.1-17
CREEP_Z = 4.0
#: a creep below this share of the deflection moves the compliance less than the readings' own uncertainty
MIN_SHARE = 0.005
#: readings of one gauge within holds the check needs on a load axis
MIN_READINGS = 20


@dataclass
class CreepCheck:
    """The creep the holds show, every load axis together.

    axes : the load axes whose on-axis readings were fitted; tau_s : the best time constant [s]; share : the creep
    at equilibrium over the elastic deflection (phi) [-]; z : its amplitude over its standard error; hold_s : the
    median hold's length [s].
    """

    axes: tuple
    tau_s: float
    share: float
    z: float
    hold_s: float

    def text(self) -> str:
        axes = ", ".join(a.value for a in self.axes)
        return (f"the rod creeps: the on-axis gauges keep moving within the holds (load axes {axes}) as a creep of "
                f"about {100 * self.share:.2g} % of the deflection with a time constant of about {self.tau_s:.2g} s "
                f"would ({self.z:.0f} standard errors): the hold means this fit takes, hence its compliance, include "
                f"part of it by how long each hold lasts ({self.hold_s:.2g} s here); `rodlab diagnose --rig` fits the "
                "creep and its --export writes the compliance without the part a hold does not complete")


@dataclass
class _Axis:
    """One load axis's readings within their holds: the on-axis readings less their hold means [mm], the drift
    column (times less their hold means) [s], the column maker of a creep, the readings' scatter [mm]."""

    axis: object
    y: np.ndarray
    drift: np.ndarray
    creep: object
    sd: float
    spans: list


def creep_within_holds(rec: RigRecording) -> CreepCheck | None:
    """The creep the holds of ``rec`` show (:data:`CREEP_Z`, :data:`MIN_SHARE`), or None."""
    axes = [a for a in (_axis_data(rec, axis) for axis in sorted(set(rec.load_axis), key=lambda a: a.value)) if a]
    if not axes:
        return None
    best = None
    for tau in CREEP_TAU_GRID_S:
        fit = _amplitude(axes, tau)
        if fit is not None and (best is None or fit[0] / fit[1] > best[1] / best[2]):
            best = (tau, fit[0], fit[1])
    if best is None or not (best[1] / best[2] > CREEP_Z and best[1] > MIN_SHARE):
        return None
    tau, phi, se = best
    return CreepCheck(tuple(a.axis for a in axes), float(tau), float(phi), float(phi / se),
                      float(np.median(sum((a.spans for a in axes), []))))


def _axis_data(rec: RigRecording, axis) -> _Axis | None:
    """One load axis's readings, or None without enough readings, holds or load changes."""
    c = axis.index
    idx = np.nonzero(np.array([a is axis for a in rec.load_axis]) & np.isfinite(rec.disp_mm[:, c]))[0]
    idx = idx[np.argsort(rec.time_s[idx], kind="stable")]
    if idx.size < MIN_READINGS or np.unique(rec.step[idx]).size < 3:
        return None
    t, y, hold, repeat = rec.time_s[idx], rec.disp_mm[idx, c], rec.step[idx], rec.repeat[idx]
    load = rec.mass_kg[idx] * G0
    if np.ptp(load) <= 0:
        return None
    within = _within_holds(hold)
    elastic = _compliance(y, load, hold) * load           # what the creep relaxes towards, per unit phi
    drift, yw = within(t), within(y)
    r = yw - drift * float(drift @ yw) / max(float(drift @ drift), 1e-300)
    sd = float(np.sqrt(r @ r / max(r.size - np.unique(hold).size - 1, 1)))
    if not sd > 0:
        return None
    return _Axis(axis, yw, drift, lambda tau: within(_series_creep(t, elastic, repeat, tau)), sd,
                 [float(np.ptp(t[hold == h])) for h in np.unique(hold)])


def _within_holds(hold: np.ndarray):
    """A function taking each hold's mean out of a column (the readings' own order)."""
    keys, inv = np.unique(hold, return_inverse=True)
    counts = np.bincount(inv, minlength=keys.size)

    def within(v: np.ndarray) -> np.ndarray:
        return v - (np.bincount(inv, weights=v, minlength=keys.size) / counts)[inv]
    return within


def _series_creep(t: np.ndarray, elastic: np.ndarray, repeat: np.ndarray, tau: float) -> np.ndarray:
    """Creep per unit phi of every reading [mm]: the elastic deflection's history in each series (a repeat: the
    rod remounted, its creep afresh) relaxed with time constant ``tau`` [s]."""
    out = np.zeros(t.size)
    for r in np.unique(repeat):
        m = repeat == r
        out[m] = relax(t[m] / tau, elastic[m])
    return out


def _amplitude(axes: list, tau: float) -> tuple[float, float] | None:
    """(phi, its standard error) of one creep of time constant ``tau`` [s] over every axis's readings, each
    whitened by its scatter, with a drift per axis; None where the columns are degenerate."""
    n = sum(a.y.size for a in axes)
    X = np.zeros((n, 1 + len(axes)))
    y = np.zeros(n)
    row = 0
    for k, a in enumerate(axes):
        m = slice(row, row + a.y.size)
        X[m, 0], X[m, 1 + k], y[m] = a.creep(tau) / a.sd, a.drift / a.sd, a.y / a.sd
        row += a.y.size
    dof = n - sum(len(a.spans) for a in axes) - X.shape[1]
    if dof < 5 or not np.all(np.linalg.norm(X, axis=0) > 0):
        return None
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    res = y - X @ coef
    cov = np.linalg.pinv(X.T @ X) * max(float(res @ res) / dof, 1.0)
    se = float(np.sqrt(max(cov[0, 0], 0.0)))
    return (float(coef[0]), se) if se > 0 else None


def _compliance(y: np.ndarray, load: np.ndarray, hold: np.ndarray) -> float:
    """The on-axis compliance [mm/N] from the hold means against their loads (the creep's share is of it)."""
    keys = np.unique(hold)
    F = np.array([load[hold == h].mean() for h in keys])
    Y = np.array([y[hold == h].mean() for h in keys])
    return float(np.polyfit(F, Y, 1)[0])
