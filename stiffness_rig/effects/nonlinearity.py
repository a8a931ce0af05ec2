"""``nonlinearity``: a load-dependent stiffness, compliance C (1 + beta |F| / 10 N)."""
from __future__ import annotations

import numpy as np

from rodlab.enums import RigEffect
from rodlab.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["Nonlinearity"]


class Nonlinearity(RigEffectModel):
    effect = RigEffect.NONLINEARITY
    params = (ParamSpec("beta_per_10N", "-", "relative change of the compliance per 10 N of load"),)
    example = {"beta_per_10N": 0.01}
    physics = "load-dependent stiffness"
    signature = "the slope changes with the load magnitude; residuals curved in the load"
    confirm = "add smaller and larger masses on this axis: the residual should stay curved in the load"

    def load_compliance(self, C, F, hold, p):
        return C * (1.0 + self.value(p, "beta_per_10N") * np.linalg.norm(F) / 10.0)

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        return [Hypothesis(self.effect, None, ["beta_per_10N"], (ctx.base * np.abs(data.F) / 10.0)[:, None],
                           [-1.0], [1.0],
                           "a load-dependent stiffness bends the load-deflection line: the slope changes with the "
                           "load")]
