"""``periodic_joint_error``: gear or encoder eccentricity, an angle error once per revolution of one joint."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["PeriodicJointError", "correct_joints"]


def correct_joints(q_rad: np.ndarray, corr: dict) -> np.ndarray:
    """Joint angles [rad], shape=(N, n), with the fitted once-per-revolution errors {joint index: (a_sin,
    a_cos) [rad]} added: the angles the joints really take."""
    q = np.array(q_rad, float, copy=True)
    for k, (a_s, a_c) in corr.items():
        q[:, k] = q[:, k] + a_s * np.sin(q_rad[:, k]) + a_c * np.cos(q_rad[:, k])
    return q


class PeriodicJointError(CampaignEffectModel):
    effect = "periodic_joint_error"
    order = 30
    params = (ParamSpec("joint", "-", "the joint (1-based)", kind="int", magnitude=False),
              ParamSpec("amp_deg", "deg", "amplitude A: the joint really turns q + A sin(q + phase)"),
              ParamSpec("phase_deg", "deg", "phase of the error", default=0.0, magnitude=False))
    example = {"joint": 4, "amp_deg": 0.006}
    physics = "gear or encoder eccentricity: the joint's angle is off by a once-per-revolution error"
    signature = "the residuals follow sin / cos of one joint's angle along that joint's motion"
    locations = ("joint:K",)
    reported = "`amp_sin_rad`, `amp_cos_rad` [rad]: joint K turns `q + a_s sin q + a_c cos q`"

    required = ("joint",)

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        if not 1 <= int(p["joint"]) <= n_joints:
            self.fail(f"effect {self.effect}: joint {p['joint']} is not one of the robot's joints 1..{n_joints}",
                      f"{self.effect}.joint")

    def joint_angles(self, q_rad: np.ndarray, p: dict) -> np.ndarray:
        k, amp, ph = int(p["joint"]) - 1, np.deg2rad(p["amp_deg"]), np.deg2rad(p["phase_deg"])
        out = np.array(q_rad, float, copy=True)
        out[..., k] += amp * np.sin(out[..., k] + ph)
        return out

    def truth(self, p: dict | None) -> dict:
        return {"periodic_joint_error": None if p is None else [int(p["joint"]), float(p["amp_deg"]),
                                                                  float(p["phase_deg"])]}

    def hypotheses(self, ctx: CampaignContext) -> list:
        fr, N, out = ctx.frames, ctx.n_points, []
        modelled = ctx.result.harmonic_range_deg                 # joints the identification already carries
        for k in range(ctx.robot.n):
            if k + 1 in modelled:
                continue
            g = np.cross(fr.z_prev[:, k], fr.p0 - fr.o_prev[:, k]) @ fr.R_W0.T       # dp/dtheta_k
            q = ctx.obs.q_rad[:, k]
            H = np.stack([g * np.sin(q)[:, None], g * np.cos(q)[:, None]], axis=-1).reshape(3 * N, 2)
            out.append(hypothesis(self.effect, f"joint:{k + 1}", ["amp_sin_rad", "amp_cos_rad"], H,
                                  f"gear or encoder eccentricity of joint {k + 1}: an angle error once per "
                                  "revolution, periodic in q"))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        k = int(location_parts(location)[1]) - 1
        fit.joint_corrections_rad[k] = (parameters["amp_sin_rad"], parameters["amp_cos_rad"])

    def remedy(self, location: str, parameters: dict) -> str:
        return (f"joint {location_parts(location)[1]} has a once-per-revolution angle error the kinematic model "
                "does not hold: have the gearbox / encoder checked, or identify it with the robot (add joint "
                f"{location_parts(location)[1]} to `rodlab calibrate --joint-harmonics`) and compensate it in the "
                "controller")
