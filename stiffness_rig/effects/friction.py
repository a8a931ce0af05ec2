"""``friction``: Coulomb friction F_f [N] in the rig's slides holds back F_f while loading and adds it while
unloading (the hold's direction of travel), splitting the branches by 2 F_f.

Back at mass 0 a rig does one of two things, and the diagnosis tries both (one term at most): the slide stays
stuck and holds the rod back by F_f (what :meth:`Friction.force` simulates), or the slide lets go with the hanger
off and the rod carries nothing (an independent simulator's rig did this: named a tare beside the friction before).
"""
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
        travel = np.where(data.unload, 1.0, -1.0) * ~data.reference
        unit = ctx.C_sim[data.comp, data.axis] * data.sign          # the deflection of 1 N along the load
        text = ("Coulomb friction in the rig's slides holds back F_f while loading and adds it while unloading, "
                "splitting the branches by 2 F_f")
        out = [Hypothesis(self.effect, None, ["F_f_N"], (travel * unit)[:, None], [0.0], [50.0], text)]
        released = travel * (data.mass > 0)
        if not np.array_equal(released, travel):
            out.append(Hypothesis(self.effect, None, ["F_f_N"], (released * unit)[:, None], [0.0], [50.0],
                                  text + "; the slide lets go at mass 0 (no force with the hanger off)"))
        return out
