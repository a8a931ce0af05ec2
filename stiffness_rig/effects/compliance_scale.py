"""``compliance_scale``: every member uniformly softer or stiffer than simulated (a modulus off): C_true = r C_sim."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["ComplianceScale"]


class ComplianceScale(RigEffectModel):
    effect = "compliance_scale"
    order = 30
    params = (ParamSpec("r", "-", "true over simulated compliance, all components"),)
    example = {"r": 1.2}
    physics = "every member uniformly softer/stiffer than simulated (modulus off)"
    signature = "all compliance components scaled by one factor r"
    confirm = "a coupon test of the tube material should give a modulus off by the fitted factor"
    structural = True

    def check(self, p: dict) -> None:
        if not p["r"] > 0:
            raise RigError(f"effect compliance_scale: r must be > 0, got {p['r']!r}", key="compliance_scale.r")

    def compliance(self, C, p, places):
        return C * float(p["r"])

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        return [Hypothesis(self.effect, None, ["r"], ctx.base[:, None], [-0.8], [4.0],
                           "every member uniformly softer or stiffer than simulated (a modulus off) scales all "
                           "compliance components by one factor r", dC=[np.asarray(ctx.C_sim, float)],
                           report_offset=[1.0])]
