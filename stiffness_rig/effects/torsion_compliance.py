"""``torsion_compliance``: pipe I twists more than simulated (a low laminate shear modulus): an extra torsion
compliance of a spring at the flange on the member axis z_T."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel
from .springs import spring_columns, spring_compliance, spring_matrices

__all__ = ["TorsionCompliance"]

_Z = np.array([0.0, 0.0, 1.0])


class TorsionCompliance(RigEffectModel):
    effect = "torsion_compliance"
    order = 50
    params = (ParamSpec("s_torsion_rad_per_Nm", "rad/(N m)", "extra torsion compliance of pipe I"),
              ParamSpec("point_T_mm", "mm", "where pipe I starts, in {T} (default: the flange)", kind="vector"),
              ParamSpec("axis", "-", "pipe I's axis in {T} (default: z_T)", kind="vector"))
    example = {"s_torsion_rad_per_Nm": 2e-4}
    physics = "tube torsion softer than simulated (laminate shear modulus)"
    signature = "excess only in the components that twist pipe I (tool y)"
    confirm = ("load along y_T only (twisting pipe I): the twist should exceed the model by the fitted factor "
               "while bending along x_T and z_T agrees")
    structural = True
    locations = ("pipe_I",)

    def compliance(self, C, p, places):
        if "point_T_mm" in p:
            pt = p["point_T_mm"]
        elif "flange_clamp" in places:
            pt = places["flange_clamp"][0]
        else:
            raise RigError("effect torsion_compliance: where pipe I starts is unknown; give point_T_mm (the flange "
                           "in {T}, i.e. minus the tool vector) or the rod's places", key="torsion_compliance.point_T_mm")
        return C + spring_compliance(pt, p.get("axis", _Z), 0.0, self.value(p, "s_torsion_rad_per_Nm") * 1e-3)

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        flange = -np.asarray(ctx.tool_mm, float)
        return [Hypothesis(self.effect, "pipe_I", ["s_torsion_rad_per_Nm"], spring_columns(data, flange, _Z)[:, 1:],
                           [0.0], [1e-2], "pipe I twists more than simulated (a low laminate shear modulus): excess "
                           "compliance only in the components that twist pipe I",
                           dC=[spring_matrices(flange, _Z)[1]], report_scale=[1e3])]
