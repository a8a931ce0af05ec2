"""``friction``: Coulomb friction F_f [N] in the rig's slides holds back F_f while loading and adds it while
unloading (the hold's direction of travel), splitting the branches by 2 F_f."""
from __future__ import annotations

import numpy as np

from rodlab.core.enums import Phase
from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["Friction"]


class Friction(RigEffectModel):
    effect = "friction"
    order = 10
    params = (ParamSpec("F_f_N", "N", "friction force in the slides"),)
    example = {"F_f_N": 0.5}
    physics = "Coulomb friction in the rig's slides"
    signature = "loading and unloading branches split by 2 F_f, independent of the load"
    confirm = ("load and unload to the same mass: the two readings should differ by the fitted 2 F_f; "
               "lubricating or tapping the slides should shrink the split")

    def force(self, F: float, hold, p: dict) -> float:
        if hold.mass_kg > 0 or hold.phase is Phase.UNLOAD:
            Ff = self.value(p, "F_f_N")
            return F - Ff if hold.phase is Phase.LOAD else F + Ff
        return F

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        brake = np.where(data.unload, 1.0, -1.0) * ~data.reference * ctx.C_sim[data.comp, data.axis] * data.sign
        return [Hypothesis(self.effect, None, ["F_f_N"], brake[:, None], [0.0], [50.0],
                           "Coulomb friction in the rig's slides holds back F_f while loading and adds it while "
                           "unloading, splitting the branches by 2 F_f")]
