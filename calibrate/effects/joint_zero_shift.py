"""``joint_zero_shift`` (rodlab's addition): one joint's zero is off at one clamping position, not in the rest.

A MultiCal campaign takes hours and re-clamps the device between positions; a robot re-homed or re-mastered in
between, a resolver or encoder that lost counts, a collision or an axis restarted after a fault leave one joint's
zero shifted by a constant from then on (until the next homing). The identification takes one ``dtheta_K`` for
the whole campaign, so the points of the shifted positions disagree with the rest by ``g_K(q) delta``: the
ball's motion per radian of joint K at each point (as a wrong fixture pose, but with one parameter per position
instead of three, and not a translation: it varies with the pose the ball is reached in). An IRB 4600 trial's
joint 2 shifted by 0.008 deg over positions 4 and 5 had been named two wrong fixture poses and three "isolated"
gross errors at those positions; freeing those fixture keys, as the diagnosis advised, worsened the held-out
error 0.107 -> 0.180 mm.

Hypotheses: one per joint and position (a joint chosen from the robot's: one hidden parameter), the world
position included (its points are as free to be re-homed as any other). A shift over several positions is one
finding per position. At a position whose fixture pose is a hypothesis too, the shift must fit clearly better than
that pose (``defers_to``, :func:`rodlab.app.diagnose.campaign_forms.deferred`): where the ball's motion per radian
of the joint hardly changes over the position's poses (joint 1: the ball stays at one place) a shift is a
translation of the position, which a wrong fixture pose, the commoner cause, gives too.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis, joint_motion_W

__all__ = ["JointZeroShift"]


class JointZeroShift(CampaignEffectModel):
    effect = "joint_zero_shift"
    order = 90
    params = (ParamSpec("position", "-", "the clamping position at which the joint's zero is off", kind="int",
                        magnitude=False),
              ParamSpec("joint", "-", "the joint (1-based)", kind="int", magnitude=False),
              ParamSpec("dtheta_deg", "deg", "the shift: at that position the joint really turns q + dtheta"))
    example = {"position": 2, "joint": 2, "dtheta_deg": 0.008}
    physics = ("one joint's zero moved between clamping positions (the robot re-homed or re-mastered, an encoder or "
               "resolver that lost counts, an axis restarted after a fault): its angle is off by a constant at "
               "that position only")
    signature = ("the residuals of one position follow one joint's motion (the ball's motion per radian of that "
                 "joint, which changes with the pose), one parameter")
    locations = ("position:J",)
    reported = "`dtheta_deg` [deg] and `joint`: at position J joint K really turns `q + dtheta`"

    required = ("position", "joint")
    repeatable = True

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        self.check_joint(p, n_joints)
        if not 1 <= int(p["position"]) <= positions:
            self.fail(f"effect {self.effect}: position {p['position']} is not one of the campaign's positions "
                      f"1..{positions}", f"{self.effect}.position")

    def same_place(self, p: dict, q: dict) -> bool:
        return int(p["position"]) == int(q["position"])

    def position_angles(self, q_rad: np.ndarray, j: int, p: dict) -> np.ndarray:
        if j != int(p["position"]):
            return q_rad
        out = np.array(q_rad, float, copy=True)
        out[..., int(p["joint"]) - 1] += np.deg2rad(float(p["dtheta_deg"]))
        return out

    def hypotheses(self, ctx: CampaignContext) -> list:
        N, pos, out = ctx.n_points, np.asarray(ctx.position), []
        positions = np.unique(pos)
        if positions.size < 2:
            return out                                    # one position: the identification's dtheta is the shift
        for k in range(ctx.robot.n):
            g = joint_motion_W(ctx.frames, k)
            for j in positions:
                H = np.where((pos == j)[:, None], g, 0.0).reshape(3 * N, 1)
                out.append(hypothesis(self.effect, f"position:{int(j)}", ["dtheta_deg"], H,
                                      f"joint {k + 1}'s zero is off at this clamping position and not at the others "
                                      "(re-homed, re-mastered or lost counts between clampings)",
                                      report_scale=np.array([180 / np.pi]), hidden=1, settings={"joint": k + 1},
                                      defers_to="fixture_pose"))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        j, k = int(location_parts(location)[1]), int(parameters["joint"]) - 1
        shift = np.zeros_like(ctx.obs.q_rad)
        shift[np.asarray(ctx.position) == j, k] = np.deg2rad(parameters["dtheta_deg"])
        fit.obs_edits.append(lambda obs: replace(obs, q_rad=obs.q_rad + shift))

    def remedy(self, location: str, parameters: dict) -> str:
        j = location_parts(location)[1]
        k = int(parameters.get("joint", 0))
        d = parameters.get("dtheta_deg")
        size = f" by {d:.3g} deg" if d is not None else ""
        return (f"joint {k}'s zero at clamping position {j} differs{size} from the rest of the campaign: look in the "
                "controller's log for a re-homing, re-mastering or axis fault at that time, keep the robot powered "
                f"and homed through the campaign, and record position {j} again (or leave it out); its fixture pose "
                "is not the cause")
