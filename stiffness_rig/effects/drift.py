"""``drift``: a zero drift of the gauges (thermal or electronic), independent of the load — a rate [mm/s] in
time since the series started, or a coefficient [mm/K] on the temperature change since then; per gauge."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["Drift"]

_AXES = "xyz"


class Drift(RigEffectModel):
    effect = "drift"
    order = 90
    params = (tuple(ParamSpec(f"rate_{a}_mm_per_s", "mm/s", f"zero drift of the {a} gauge in time") for a in _AXES)
              + tuple(ParamSpec(f"{a}_mm_per_K", "mm/K", f"zero drift of the {a} gauge with temp_C") for a in _AXES))
    # 1e-5 mm/s: ~5 um over a standard series, clearly above a gauge's ~0.6 um noise (a visible example)
    example = {f"rate_{a}_mm_per_s": 1e-5 for a in _AXES}
    physics = "thermal or electronic zero drift"
    signature = ("an offset that follows the time since the series start (`time`) or temp_C (`temp`, when it varies "
                 "by more than 0.05 K), independent of the load")
    confirm = "record the unloaded rod for as long as a run (log temp_C): its zero should move at the fitted rate"
    locations = ("time", "temp")

    def reading(self, x, t, dtemp_K, p):
        rate = np.array([self.value(p, f"rate_{a}_mm_per_s") for a in _AXES])
        per_K = np.array([self.value(p, f"{a}_mm_per_K") for a in _AXES])
        return x + rate * t + per_K * dtemp_K

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        comps = sorted(set(data.comp.tolist()))
        k = len(comps)
        out = [Hypothesis(self.effect, "time", [f"rate_{_AXES[c]}_mm_per_s" for c in comps],
                          np.column_stack([(data.comp == c) * data.t_series for c in comps]), np.full(k, -1.0),
                          np.full(k, 1.0), "a zero drift of the gauges (thermal or electronic) that follows time, "
                                           "independent of the load")]
        if np.isfinite(data.temp).all() and np.ptp(data.temp) > 0.05:
            # relative to the series start (the gauges are zeroed there)
            out.append(Hypothesis(self.effect, "temp", [f"{_AXES[c]}_mm_per_K" for c in comps],
                                  np.column_stack([(data.comp == c) * data.temp for c in comps]), np.full(k, -1.0),
                                  np.full(k, 1.0), "a zero drift of the gauges that follows the temperature, "
                                                   "independent of the load"))
        return out
