"""``lost_motion``: backlash of one joint's gear, an angle error that flips with the direction the joint was last
moved in (rodlab's addition to the contract's vocabulary; ``rodlab diagnose --points`` tests the same for
instrument points).

The direction of each point is the sign of the joint's last move before it within its clamping position, in the
order the points were recorded (``time_s`` when the campaign has it, else the file's order); before the joint's
first move at a position (the robot came from the last position, through the device's re-alignment) it is
unknown, and the residual chooses it, one choice per position (each a hidden parameter in the BIC). A joint whose
static torque keeps one sign sits on one gear flank whatever its approach (gravity): it is not tested.
A gear's backlash read as a once-per-revolution error had been named ``periodic_joint_error`` with outliers.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis, joint_motion_W

__all__ = ["LostMotion", "approach_directions"]


def approach_directions(q_rad: np.ndarray, order: np.ndarray | None = None) -> np.ndarray:
    """+1 / -1: the direction each joint last moved in before each point, 0 before its first move; ``q_rad``
    (N, n) [rad] in the file's order, visited in ``order`` (indices; None: the file's order). Shape (N, n)."""
    q = np.asarray(q_rad, float)
    idx = np.arange(len(q)) if order is None else np.asarray(order)
    step = np.sign(np.diff(q[idx], axis=0, prepend=q[idx][:1]))
    last = np.zeros_like(step)
    for i in range(len(idx)):
        last[i] = np.where(step[i] != 0, step[i], last[i - 1] if i else 0.0)
    out = np.zeros_like(q)
    out[idx] = last
    return out


def _directions(ctx: CampaignContext) -> np.ndarray:
    """:func:`approach_directions` within each clamping position, in recording order, shape (N, n)."""
    t = ctx.time_s
    timed = t is not None and np.isfinite(t).all() and np.ptp(t) > 0
    out = np.zeros_like(ctx.obs.q_rad)
    for j in np.unique(ctx.position):
        rows = np.flatnonzero(ctx.position == j)
        order = np.argsort(t[rows], kind="stable") if timed else None
        out[rows] = approach_directions(ctx.obs.q_rad[rows], order)
    return out


def _unknown_from_residual(s: np.ndarray, g: np.ndarray, resid: np.ndarray, position: np.ndarray) -> np.ndarray:
    """``s`` (N,) with the unknown directions (0: before the joint's first move at a clamping position, the robot
    came from the last one) set, one for each position's run of them, to the one the residual ``resid`` (N, 3)
    [mm] points to, given the play the known points show along the joint's motion ``g`` (N, 3) [mm/rad]."""
    out = s.astype(float).copy()
    unknown = out == 0
    if not unknown.any():
        return out
    along = np.einsum("ij,ij->i", g, resid)
    half_play = float(np.sum(along[~unknown] * out[~unknown]) / max(np.sum(g[~unknown] ** 2), 1e-300))
    for j in np.unique(position[unknown]):
        run = unknown & (position == j)
        out[run] = 1.0 if float(np.sum(along[run])) * half_play >= 0 else -1.0
    return out


def _signs(ctx: CampaignContext, k: int, g: np.ndarray, s: np.ndarray | None = None) -> np.ndarray:
    """The approach direction of joint ``k`` at every point, the unknown ones chosen from the residual (the
    hypothesis and the re-identification use the same); ``g``: the joint's motion [mm/rad]; ``s``:
    :func:`_directions`, when at hand."""
    s = _directions(ctx) if s is None else s
    return _unknown_from_residual(s[:, k], g, ctx.result.residuals_mm, np.asarray(ctx.position))


def _one_flank(tau: np.ndarray) -> bool:
    """The joint's static torque keeps one sign well away from zero: gravity holds its gear on one flank, so the
    approach direction does not change where it sits."""
    return bool(np.all(tau > TORQUE_FLANK_NM) or np.all(tau < -TORQUE_FLANK_NM))


#: a joint whose static torque stays beyond this [N m] on one side sits on one gear flank whatever its approach
TORQUE_FLANK_NM = 5.0


class LostMotion(CampaignEffectModel):
    effect = "lost_motion"
    order = 70
    params = (ParamSpec("joint", "-", "the joint (1-based)", kind="int", magnitude=False),
              ParamSpec("lost_motion_deg", "deg", "the gear's play b: the joint stops b/2 short of or past its "
                                                  "reading, by the direction it was last moved in"))
    example = {"joint": 4, "lost_motion_deg": 0.02}
    physics = "backlash (lost motion) in one joint's gear: its angle depends on the direction it was approached from"
    signature = ("the residuals follow that joint's motion and flip sign with the direction the joint was last moved "
                 "in (in the order the points were recorded)")
    locations = ("joint:K",)
    reported = ("`lost_motion_deg` [deg]: joint K's angle is off by +-b/2 with the direction it was last moved in (b > 0: "
                "past its reading in that direction; a gear behind a motor-side encoder lags: b < 0); not tested on a "
                "joint whose static torque keeps one sign (gravity holds its gear on one flank)")
    required = ("joint",)

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        self.check_joint(p, n_joints)

    def joint_angles(self, q_rad: np.ndarray, p: dict) -> np.ndarray:
        """The simulator's points of one clamping position, in their order; the first is approached upwards (the
        diagnosis does not know that)."""
        k = int(p["joint"]) - 1
        out = np.array(q_rad, float, copy=True)
        s = approach_directions(np.atleast_2d(q_rad))[..., k]
        out[..., k] += 0.5 * np.deg2rad(p["lost_motion_deg"]) * np.where(s == 0, 1.0, s)
        return out

    def hypotheses(self, ctx: CampaignContext) -> list:
        fr, N, out = ctx.frames, ctx.n_points, []
        s, pos = _directions(ctx), np.asarray(ctx.position)
        for k in range(ctx.robot.n):
            if np.unique(s[:, k][s[:, k] != 0]).size < 2:
                continue                                             # never moved both ways: not testable
            if ctx.tau_Nm is not None and _one_flank(ctx.tau_Nm[:, k]):
                continue
            g = joint_motion_W(fr, k)
            H = (g * (0.5 * _signs(ctx, k, g, s))[:, None]).reshape(3 * N, 1)
            out.append(hypothesis(self.effect, f"joint:{k + 1}", ["lost_motion_deg"], H,
                                  f"backlash in joint {k + 1}'s gear: its angle is off by half the play, with the "
                                  "sign of the direction it was last moved in", report_scale=np.array([180 / np.pi]),
                                  hidden=int(np.unique(pos[s[:, k] == 0]).size)))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        k = int(location_parts(location)[1]) - 1
        shift = np.zeros_like(ctx.obs.q_rad)
        shift[:, k] = 0.5 * np.deg2rad(parameters["lost_motion_deg"]) * _signs(ctx, k, joint_motion_W(ctx.frames, k))
        fit.obs_edits.append(lambda obs: replace(obs, q_rad=obs.q_rad + shift))

    def remedy(self, location: str, parameters: dict) -> str:
        j = location_parts(location)[1]
        b = parameters.get("lost_motion_deg")
        size = f" of {abs(b):.3g} deg" if b is not None else ""
        return (f"joint {j} has backlash{size}: approach every point from the same direction (a short pre-move "
                f"of joint {j}), in the campaign and in use, or have its gearbox checked")
