"""``compliance_scale``: every member uniformly softer or stiffer than simulated (a modulus off): C_true = r C_sim."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["ComplianceScale", "PLAUSIBLE_R"]

#: factors a modulus off (a wrong laminate, a wrong material) gives; beyond them a units slip is likelier
PLAUSIBLE_R = (0.2, 5.0)


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

    def caution(self, p: dict) -> str | None:
        r = float(p.get("r", 1.0))
        if PLAUSIBLE_R[0] <= r <= PLAUSIBLE_R[1]:
            return None
        return (f"r = {r:.3g} is beyond what any material or lay-up gives ({PLAUSIBLE_R[0]:g}-{PLAUSIBLE_R[1]:g}): check the "
                "recording's units (mass_kg in kg, not g; a load cell's force_N in N, not kgf or lbf; disp_*_mm in mm, "
                "not um) and that the simulation is this rod's")

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        # r from 0.001 to 1000: a units slip (g for kg, um for mm) is fitted and named, not clipped
        return [Hypothesis(self.effect, None, ["r"], ctx.base[:, None], [-0.999], [999.0],
                           "every member uniformly softer or stiffer than simulated (a modulus off) scales all "
                           "compliance components by one factor r", dC=[np.asarray(ctx.C_sim, float)],
                           report_offset=[1.0])]
