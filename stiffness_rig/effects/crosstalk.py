"""``crosstalk``: a gauge tilted by a small angle eps [rad] towards another axis reads cos(eps) of its own
displacement plus sin(eps) of the other one's — a reading the rod's compliance cannot produce."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["Crosstalk"]

_AXES = "xyz"


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
                # the c gauge picks up eps x the true displacement along j (the simulated one)
                col = np.zeros(data.y.size)
                m = data.comp == c
                col[m] = ctx.C_sim[j, data.axis[m]] * data.F[m]
                out.append(Hypothesis(self.effect, f"sensor:{_AXES[c]}", [f"eps_{_AXES[j]}_rad"], col[:, None],
                                      [-0.2], [0.2],
                                      f"the {_AXES[c]} gauge is not aligned with its axis and reads a fraction of "
                                      f"the {_AXES[j]} displacement, which the rod's compliance cannot produce"))
        return out
