"""``crosstalk``: a gauge tilted by a small angle eps [rad] towards another axis reads cos(eps) of its own
displacement plus sin(eps) of the other one's — a reading the rod's compliance cannot produce.

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
#: the largest tilt the hypothesis considers [rad] (its bound: a gauge off by more is visible by eye)
_EPS_MAX = 0.2


class Crosstalk(RigEffectModel):
    effect = "crosstalk"
    order = 80
    params = ((ParamSpec("sensor", "-", "the tilted gauge", "z", kind="str", choices=tuple(_AXES)),)
              + tuple(ParamSpec(f"eps_{a}_rad", "rad", f"tilt of the gauge towards {a}_T (set one)") for a in _AXES))
    example = {"eps_y_rad": 0.01}
    physics = "a displacement sensor not aligned with its axis"
    signature = "a perpendicular reading that the rod's compliance cannot produce"
    confirm = "check the gauge's alignment with a square or turn it on its mount: the cross reading should change"
    locations = ("sensor:x", "sensor:y", "sensor:z")

    def example_for(self, p: dict) -> dict:
        """A 0.01 rad tilt towards y, or towards z for the y gauge."""
        return {"eps_z_rad" if p.get("sensor", "z") == "y" else "eps_y_rad": 0.01}

    def _tilt(self, p: dict) -> tuple[int, int, float]:
        i = _AXES.index(p["sensor"])
        tilts = [(j, float(p[f"eps_{a}_rad"])) for j, a in enumerate(_AXES) if f"eps_{a}_rad" in p]
        return i, tilts[0][0], tilts[0][1]

    def check(self, p: dict) -> None:
        set_ = [a for a in _AXES if f"eps_{a}_rad" in p]
        if len(set_) != 1 or set_[0] == p["sensor"]:
            raise RigError(f"effect crosstalk: give one tilt eps_<axis>_rad towards an axis other than the sensor "
                           f"{p['sensor']!r}, got {[f'eps_{a}_rad' for a in set_]}", key="crosstalk.eps")

    def reading(self, x, t, dtemp_K, p):
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
                cross, own = np.zeros(data.y.size), np.zeros(data.y.size)
                cross[m] = ctx.C_sim[j, data.axis[m]] * data.F[m]
                own[m] = ctx.base[m]
                col = cross + _cos_slope(_tilt_estimate(data.y[m] - own[m], cross[m], own[m])) * own
                out.append(Hypothesis(self.effect, f"sensor:{_AXES[c]}", [f"eps_{_AXES[j]}_rad"], col[:, None],
                                      [-_EPS_MAX], [_EPS_MAX],
                                      f"the {_AXES[c]} gauge is not aligned with its axis and reads a fraction of "
                                      f"the {_AXES[j]} displacement, which the rod's compliance cannot produce"))
        return out


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
