"""``crosstalk``: a gauge tilted by a small angle eps [rad] towards another axis reads cos(eps) of its own
displacement plus sin(eps) of the other one's — a reading the rod's compliance cannot produce.

Its second form (rodlab's, parameter ``load``): the load's line is tilted instead (a pulley or hanger off the
axis): during the holds of that load direction the rod carries cos(eps) of the load along the axis and sin(eps)
of it along another, so every gauge read in that series sees C_F times that side force. It differs from a tilted
gauge where a gauge is read under two load axes: the tilted gauge errs in both series, the tilted load in its own.

The hypothesis keeps both terms: its one column is the cross displacement plus (cos(eps) - 1) / eps of the
gauge's own, at a first estimate of eps from the recording itself (the fitted coefficient is then eps to second
order). Linear in eps alone, a tilt of 0.05-0.2 rad on a stiff rod leaves cos(eps) - 1 of the main reading
(-0.1 to -2 %), which the diagnosis read as an extra compliance scale and a joint term."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["Crosstalk"]

_AXES = "xyz"
_LOADS = ("x", "-x", "y", "-y", "z", "-z")
#: a rod's own cross compliance reads like a tilted gauge in one series (a paper-rod trial: a laminate's bend-twist
#: coupling, c23 6 % of c22, had been named three tilted gauges and removed from the export)
_COUPLING = ("if it does not change, the rod itself may couple the two directions (a laminate's bend-twist "
             "coupling, a bond that twists under bending: a cross compliance the design lacks): read the other gauge "
             "under the other load too; a coupling reads there alike (c_mn = c_nm), a tilted gauge does not, and "
             "then keep the measured entry (`rig fit`) instead of the export")
#: the largest tilt the hypothesis considers [rad] (its bound: a gauge off by more is visible by eye)
_EPS_MAX = 0.2


class Crosstalk(RigEffectModel):
    effect = "crosstalk"
    order = 80
    params = ((ParamSpec("sensor", "-", "the tilted gauge (default z)", kind="str", choices=tuple(_AXES)),
               ParamSpec("load", "-", "instead of a gauge: the load direction whose line is tilted", kind="str",
                         choices=_LOADS))
              + tuple(ParamSpec(f"eps_{a}_rad", "rad", f"tilt of the gauge (or the load's line) towards {a}_T (set one)")
                      for a in _AXES))
    example = {"eps_y_rad": 0.01}
    physics = "a displacement sensor not aligned with its axis"
    signature = ("a perpendicular reading that the rod's compliance cannot produce; rodlab's second form, a load line "
                 "off its axis (`load:<direction>`), is a side force in that load's series only; where the data cannot "
                 "tell a tilted gauge from a tilted load the location names both (`sensor:z|load:y`)")
    confirm = "check the gauge's alignment with a square or turn it on its mount: the cross reading should change"
    locations = ("sensor:x", "sensor:y", "sensor:z") + tuple(f"load:{a}" for a in _LOADS)

    def confirm_for(self, location):
        places = (location or "").split("|")
        load = ("check the load's line against the axis (a plumb line or a square at the pulley and the ball) and "
                "realign it: the side readings of that series should go")
        if all(p.startswith("load:") for p in places):
            return load
        gauge = self.confirm + "; " + _COUPLING
        if any(p.startswith("load:") for p in places):
            return gauge + "; or " + load
        return gauge

    def complete(self, given: dict) -> dict:
        """As :meth:`EffectSchema.complete`, the gauge ``z`` tilted unless a gauge or a load is named."""
        given = dict(given)
        if "load" not in given and "sensor" not in given:
            given["sensor"] = "z"
        return super().complete(given)

    def example_for(self, p: dict) -> dict:
        """A 0.01 rad tilt towards y, or towards z for the y gauge or a load along y."""
        axis = p["load"][-1] if "load" in p else p.get("sensor", "z")
        return {"eps_z_rad" if axis == "y" else "eps_y_rad": 0.01}

    def _tilt(self, p: dict) -> tuple[int, int, float]:
        i = _AXES.index(p["sensor"])
        tilts = [(j, float(p[f"eps_{a}_rad"])) for j, a in enumerate(_AXES) if f"eps_{a}_rad" in p]
        return i, tilts[0][0], tilts[0][1]

    def check(self, p: dict) -> None:
        set_ = [a for a in _AXES if f"eps_{a}_rad" in p]
        if "load" in p:
            if "sensor" in p:
                raise RigError("effect crosstalk: give either sensor (a tilted gauge) or load (a tilted load line), "
                               "not both", key="crosstalk.load")
            if len(set_) != 1 or set_[0] == p["load"][-1]:
                raise RigError(f"effect crosstalk: give one tilt eps_<axis>_rad of the load's line towards an axis "
                               f"other than its own {p['load']!r}, got {[f'eps_{a}_rad' for a in set_]}",
                               key="crosstalk.eps")
            return
        if len(set_) != 1 or set_[0] == p["sensor"]:
            raise RigError(f"effect crosstalk: give one tilt eps_<axis>_rad towards an axis other than the sensor "
                           f"{p['sensor']!r}, got {[f'eps_{a}_rad' for a in set_]}", key="crosstalk.eps")

    def load_line(self, F, hold, p):
        if p.get("load") != hold.axis.value:
            return F
        _, j, eps = self._tilt({**p, "sensor": p["load"][-1]})
        along = float(F[hold.axis.index] * hold.axis.sign)      # the load along its line (< 0: a net push)
        out = np.cos(eps) * F
        out[j] += np.sin(eps) * along
        return out

    def reading(self, x, t, dtemp_K, p):
        if "load" in p:
            return x
        i, j, eps = self._tilt(p)
        xi = np.cos(eps) * x[i] + np.sin(eps) * x[j]
        x = x.copy()
        x[i] = xi
        return x

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        out = []
        comps = sorted(set(data.comp.tolist()))
        for c in comps:
            for j in (j for j in comps if j != c):
                # the c gauge reads sin(eps) x the true displacement along j (the simulated one) and cos(eps) of
                # its own: eps x (x_j + k x_c) with k = (cos(eps) - 1) / eps at this recording's own estimate of eps
                m = data.comp == c
                col = _tilt_column(data, ctx, m, ctx.C_sim[j, data.axis[m]] * data.F[m])
                out.append(Hypothesis(self.effect, f"sensor:{_AXES[c]}", [f"eps_{_AXES[j]}_rad"], col[:, None],
                                      [-_EPS_MAX], [_EPS_MAX],
                                      f"the {_AXES[c]} gauge is not aligned with its axis and reads a fraction of "
                                      f"the {_AXES[j]} displacement, which the rod's compliance cannot produce"))
        return out + _load_tilts(self.effect, data, ctx)


def _load_tilts(effect, data, ctx) -> list[Hypothesis]:
    """A tilted load line per load direction of the recording and side axis: the rod carries sin(eps) of the load
    along the side axis j (every gauge of that series reads C_sim[gauge, j] x F x sin(eps), F the load along its
    line) and cos(eps) along its own, one column as for a tilted gauge."""
    out = []
    for a, sign in sorted(set(zip(data.axis.tolist(), data.sign.tolist()))):
        m = (data.axis == a) & (data.sign == sign)
        name = ("-" if sign < 0 else "") + _AXES[a]
        for j in (j for j in range(3) if j != a):
            col = _tilt_column(data, ctx, m, ctx.C_sim[data.comp[m], j] * data.F[m] * data.sign[m])  # load along line
            out.append(Hypothesis(effect, f"load:{name}", [f"eps_{_AXES[j]}_rad"], col[:, None], [-_EPS_MAX],
                                  [_EPS_MAX], f"the load along {name} is not on its axis: its line leans towards "
                                  f"{_AXES[j]}, so the rod also carries a side force along {_AXES[j]} that the load "
                                  "schedule does not state"))
    return out


def _tilt_column(data, ctx, m: np.ndarray, cross_m: np.ndarray) -> np.ndarray:
    """A tilt's column over all samples, zero outside ``m``: the cross reading per unit sin(eps) ``cross_m`` [mm] on
    the samples ``m``, plus (cos(eps) - 1) / eps of their own simulated reading at this recording's own estimate of
    eps (the fitted coefficient is then eps to second order)."""
    cross, own = np.zeros(data.y.size), np.zeros(data.y.size)
    cross[m] = cross_m
    own[m] = ctx.base[m]
    return cross + _cos_slope(_tilt_estimate(data.y[m] - own[m], cross[m], own[m])) * own


def _tilt_estimate(r: np.ndarray, cross: np.ndarray, own: np.ndarray) -> float:
    """A first estimate of the tilt [rad] from one gauge's residuals ``r`` [mm]: their least-squares fit by
    sin(eps) x the cross displacement and (cos(eps) - 1) x the gauge's own (both free here), within the
    hypothesis's bounds; 0 where the readings cannot tell."""
    A = np.column_stack([cross, own])
    if r.size < 3 or not np.all(np.isfinite(r)) or np.linalg.matrix_rank(A) < 2:
        return 0.0
    s = float(np.linalg.lstsq(A, r, rcond=None)[0][0])
    return float(np.arcsin(np.clip(s, -np.sin(_EPS_MAX), np.sin(_EPS_MAX))))


def _cos_slope(eps: float) -> float:
    """(cos(eps) - 1) / eps: the own-displacement share per unit tilt at ``eps`` [rad] (-eps / 2 when small)."""
    return float((np.cos(eps) - 1.0) / eps) if abs(eps) > 1e-12 else 0.0
