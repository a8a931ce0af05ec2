"""``tare``: a dead load [kg] (hanger, loading frame) missing from ``mass_kg`` whenever the hanger is on."""
from __future__ import annotations

from rodlab.core.hypothesis import Hypothesis, ParamSpec
from rodlab.core.units import G0

from .base import RigEffectModel

__all__ = ["Tare"]


class Tare(RigEffectModel):
    effect = "tare"
    order = 20
    params = (ParamSpec("tare_kg", "kg", "dead load on the rod whenever a mass hangs, missing from mass_kg"),)
    example = {"tare_kg": 0.05}
    physics = "a dead load missing from mass_kg (hanger, loading frame)"
    signature = "the same offset on both branches; the lines cross the load axis at -tare g0"
    confirm = "weigh the hanger and loading frame and add it to mass_kg: the offset should vanish"

    def mass(self, m: float, hold, p: dict) -> float:
        return m + self.value(p, "tare_kg") if hold.mass_kg > 0 else m

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        hanger = data.mass > 0
        return [Hypothesis(self.effect, None, ["tare_kg"],
                           (hanger * ctx.C_sim[data.comp, data.axis] * data.sign * G0)[:, None], [-5.0], [5.0],
                           "a dead load missing from mass_kg (hanger or loading frame) offsets both branches "
                           "equally")]
