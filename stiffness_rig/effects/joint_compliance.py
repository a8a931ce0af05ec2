"""``joint_compliance``: a compliant joint (bond, clamp, thread) modelled as rigid — a rotational spring at one
place of the rod (bending s_b across the member, torsion s_t about it)."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel
from .springs import spring_columns, spring_compliance, spring_matrices

__all__ = ["JointCompliance", "PLACES"]

#: location keys of a joint spring (ring 2 and the ball holder cannot be told apart from ring 1 by tip loads)
PLACES = ("flange_clamp", "ring_1", "pipe_II")


class JointCompliance(RigEffectModel):
    effect = "joint_compliance"
    order = 60
    params = (ParamSpec("location", "-", "where the spring sits", "ring_1", kind="str", choices=PLACES),
              ParamSpec("s_bend_rad_per_Nm", "rad/(N m)", "bending compliance of the joint"),
              ParamSpec("s_torsion_rad_per_Nm", "rad/(N m)", "torsion compliance of the joint", 0.0),
              ParamSpec("point_T_mm", "mm", "the spring's point in {T} (default: the location's)", kind="vector"),
              ParamSpec("axis", "-", "the member's axis in {T} (default: the location's)", kind="vector"))
    example = {"s_bend_rad_per_Nm": 4e-6, "s_torsion_rad_per_Nm": 1.6e-6}
    physics = "a compliant joint (bond, clamp, thread) modelled as rigid"
    signature = ("excess compliance whose pattern over C_F fits a rotational spring at one place; where the data "
                 "cannot tell two places apart the location names the group (`ring_1|flange_clamp`) and "
                 "`evidence.separate_by` the measurement that would; no torsion term when the member points at "
                 "the ball")
    confirm = "a dial gauge on each side of the named joint should show the angle jump there"
    structural = True
    locations = PLACES

    def place_caution(self, location: str | None) -> str | None:
        """A joint at the flange clamp is where the rod is mounted: on the rig that compliance may be the rig's
        mount (a designer trial: a clamp of the rig put c11 +60 % into the rod's file without a word)."""
        if "flange_clamp" not in (location or "").split("|"):
            return None
        return ("the flange clamp is where the rod is mounted: on the rig, part or all of this compliance may be the "
                "rig's mount, which the robot's flange does not have; before it goes into the rod's file (`diagnose "
                "--export`, `rodlab update`), re-clamp the rod (torque as on the robot) and measure again, or check "
                "the rig's mount with a stiff dummy rod")

    def compliance(self, C, p, places):
        pt, ax = self.place(p, places, p.get("location", "ring_1"))
        return C + spring_compliance(pt, ax, self.value(p, "s_bend_rad_per_Nm") * 1e-3,
                                     self.value(p, "s_torsion_rad_per_Nm") * 1e-3)

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        out = []
        for loc, (pt, ax) in ctx.places.items():
            Cb, Ct = spring_matrices(pt, ax)
            X = spring_columns(data, pt, ax)
            names, dC = ["s_bend_rad_per_Nm", "s_torsion_rad_per_Nm"], [Cb, Ct]
            if np.abs(Ct).max() < 1e-9 * np.abs(Cb).max():
                # the member points at the ball: its torsion moves no reading and cannot be identified
                X, names, dC = X[:, :1], names[:1], dC[:1]
            out.append(Hypothesis(self.effect, loc, names, X, np.zeros(len(names)), np.full(len(names), 1e-2),
                                  f"a compliant joint (bond, clamp or thread) at {loc} acts as a rotational spring "
                                  f"whose excess compliance grows with the lever from {loc} to the ball", dC=dC,
                                  report_scale=np.full(len(names), 1e3)))
        return out
