"""``load_hysteresis`` (rodlab's addition to the vocabulary): the rod is more compliant on the way down than on
the way up (hysteresis of a bond or a clamped joint), so the unloading branch lies above the loading one by a
split that grows in proportion to the load: the unloading compliance is (1 + eta) C.

Friction splits the branches by a constant 2 F_f C whatever the load; a nonlinearity bends both branches the
same way; creep's split depends on how long the holds last. This split is zero at no load and proportional
to it, the same in every hold.
"""
from __future__ import annotations

from rodlab.core.enums import Phase
from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["LoadHysteresis"]


class LoadHysteresis(RigEffectModel):
    effect = "load_hysteresis"
    order = 100
    params = (ParamSpec("eta", "-", "extra compliance on the unloading branch, relative to loading"),)
    example = {"eta": 0.01}
    physics = "load hysteresis of a bond or clamped joint"
    signature = "the unloading branch lies above the loading one by a split proportional to the load"
    confirm = ("load to each mass from below and from above: the two readings should differ by the fitted "
               "eta times the deflection, more at higher load")

    def load_compliance(self, C, F, hold, p):
        return C * (1.0 + self.value(p, "eta")) if hold.phase is Phase.UNLOAD else C

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        return [Hypothesis(self.effect, None, ["eta"], (ctx.base * data.unload)[:, None], [-0.5], [0.5],
                           "the rod is more compliant on the way down than on the way up (hysteresis of a bond or "
                           "a clamped joint): the unloading branch lies above the loading one by a split "
                           "proportional to the load")]
