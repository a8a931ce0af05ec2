"""``load_hysteresis`` (rodlab's addition to the vocabulary): the rod is more compliant on the way down than on
the way up (hysteresis of a bond or a clamped joint). Two forms:

- ``eta``: the unloading branch lies above the loading one by a split that grows in proportion to the load: the
  unloading compliance is (1 + eta) C;
- ``eta_loop``: micro-slip in a clamped or bonded joint, a symmetric loop (phenomenological) that closes at no
  load and at the series' top load: the branches lie -+ eta_loop C F (1 - F / F_top) about the line, widest
  half-way (an instrument trial's own rig read as friction, a nonlinearity and a tare, each "decisive").

Friction splits the branches by a constant 2 F_f C whatever the load; a nonlinearity bends both branches the
same way; creep's split depends on how long the holds last. These splits are zero at no load and the same in
every hold.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.enums import Phase
from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["LoadHysteresis", "loop_shape"]


class LoadHysteresis(RigEffectModel):
    effect = "load_hysteresis"
    order = 100
    params = (ParamSpec("eta", "-", "extra compliance on the unloading branch, relative to loading"),
              ParamSpec("eta_loop", "-", "a loop closing at no load and the top load: the branches lie -+ eta_loop "
                                         "C F (1 - F / F_top) about the line (micro-slip; a symmetric, phenomenological loop)"),
              ParamSpec("top_kg", "kg", "the top load of the loop (eta_loop; default: the plan's largest mass)",
                        magnitude=False))
    example = {"eta": 0.01}
    physics = "load hysteresis of a bond or clamped joint"
    signature = ("the unloading branch lies above the loading one by a split proportional to the load, or by one "
                 "that closes at the top load (a loop)")
    confirm = ("load to each mass from below and from above: the two readings should differ by the fitted "
               "eta times the deflection, more at higher load (eta_loop: most half-way to the top load)")

    def load_compliance(self, C, F, hold, p):
        C = C * (1.0 + self.value(p, "eta")) if hold.phase is Phase.UNLOAD else C
        loop, top = self.value(p, "eta_loop"), self.value(p, "top_kg")
        if loop and top > 0:
            side = 1.0 if hold.phase is Phase.UNLOAD else -1.0
            C = C * (1.0 + side * loop * max(1.0 - hold.mass_kg / top, 0.0))
        return C

    def with_plan(self, p: dict, masses) -> dict:
        if self.value(p, "eta_loop") and not self.value(p, "top_kg"):
            return {**p, "top_kg": float(max(masses))}
        return p

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        return [Hypothesis(self.effect, None, ["eta"], (ctx.base * data.unload)[:, None], [-0.5], [0.5],
                           "the rod is more compliant on the way down than on the way up (hysteresis of a bond or "
                           "a clamped joint): the unloading branch lies above the loading one by a split "
                           "proportional to the load"),
                Hypothesis(self.effect, None, ["eta_loop"], (ctx.base * loop_shape(data))[:, None], [-0.5], [0.5],
                           "a hysteresis loop that closes at no load and at the top load (micro-slip in a clamped or "
                           "bonded joint): the unloading branch lies above the loading one, most half-way up")]


def loop_shape(data) -> np.ndarray:
    """Per sample, -+ (1 - |F| / F_top) (+ unloading), F_top the largest load of its series: the loop's split per
    unit eta_loop, relative to the deflection."""
    F = np.abs(np.asarray(data.F, float))
    top = np.zeros_like(F)
    for g in np.unique(data.zero_groups):
        m = data.zero_groups == g
        top[m] = F[m].max()
    share = np.where(top > 0, 1.0 - F / np.where(top > 0, top, 1.0), 0.0)
    return np.where(data.unload, 1.0, -1.0) * share
