"""``joint_stiffening``: one joint's gear is not a linear spring: its compliance changes with the torque it carries
(a harmonic drive or a preloaded gear stiffens under load), so its angle departs from the model's ``c tau`` by
``-s tau abs(tau)`` (rodlab's addition to the contract's vocabulary).

On a joint that turns less than a revolution (the TX90's joints 2 and 3 in a MultiCal campaign) such an error is
a smooth function of the angle, and a periodic error of that joint fitted it about as well: an independent
simulator's torque-stiffened joint 2 had been named ``periodic_joint_error``. The two compete on the torque, which
gravity and the rod's weight give each point, against the angle.

A spring that stiffens until it is nearly rigid (a hardening spring ``c tau / (1 + abs(tau) / tau_s)``) departs from
``c tau`` by ``-s tau abs(tau) / (1 + abs(tau) / tau_s)`` with ``s = c / tau_s``: the same family with a saturation
torque ``tau_s`` (``saturation_Nm``; none: the quadratic). The diagnosis tries the quadratic and saturation torques of
1/8 to 2 times the joint's largest torque in the campaign (a grid: one hidden parameter in the BIC).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis, joint_motion_W

__all__ = ["JointStiffening", "stiffening_turn", "TorqueCorrection"]

#: torques of a joint that spread less than this [N m] over the campaign cannot show a non-linear spring
MIN_TORQUE_SPAN_NM = 5.0
#: saturation torques the diagnosis tries, as multiples of the joint's largest torque in the campaign
SATURATION_GRID = (0.125, 0.25, 0.5, 1.0, 2.0)


def stiffening_turn(tau_Nm: np.ndarray, s: float, saturation_Nm: float | None = None) -> np.ndarray:
    """The joint's turn beyond its linear spring [rad] under its static torque ``tau_Nm`` [N m]:
    ``-s tau abs(tau)``, or with a saturation torque ``-s tau abs(tau) / (1 + abs(tau) / saturation_Nm)`` (None
    or 0: none)."""
    t = np.asarray(tau_Nm, float)
    quad = t * np.abs(t)
    if not saturation_Nm or not np.isfinite(saturation_Nm):
        return -s * quad
    return -s * quad / (1.0 + np.abs(t) / float(saturation_Nm))


@dataclass(frozen=True)
class TorqueCorrection:
    """A non-linear joint spring as the re-identification applies it: the joint turns by
    :func:`stiffening_turn` beyond its linear spring, whole or less the part linear in the torque (its
    least-squares slope over the campaign's torques), which the joint's compliance c then carries. A saturating
    form is nearly ``-s tau_s tau`` beyond the saturation torque: where the selection found it with c free to
    take that slope back, applying it whole asks c to fall by ``s tau_s``, which the regularised c of a wrist joint
    cannot (a backlash that follows the torque's sign, found as joint 5's stiffening, had made the fit 10x worse:
    new-user trial, 2026-11-28); where the joint's linear spring itself is off, the whole turn is right. The
    re-identification tries both (:attr:`~rodlab.calibrate.effects.base.Refit.torque_linear_to_c`).

    s_rad_per_Nm2 : s [rad/(N m)^2]; saturation_Nm : tau_s [N m] or None (the quadratic);
    linear_rad_per_Nm : the slope taken out [rad/(N m)], carried by c
    """

    s_rad_per_Nm2: float
    saturation_Nm: float | None
    linear_rad_per_Nm: float

    @classmethod
    def over(cls, tau_Nm: np.ndarray, s: float, saturation_Nm: float | None, linear_to_c: bool) -> "TorqueCorrection":
        """The correction over the campaign's torques ``tau_Nm`` [N m], with its linear part left to c when
        ``linear_to_c``."""
        t = np.asarray(tau_Nm, float)
        turn = stiffening_turn(t, s, saturation_Nm)
        slope = float(t @ turn / (t @ t)) if linear_to_c and np.any(t) else 0.0
        return cls(float(s), None if saturation_Nm is None else float(saturation_Nm), slope)

    def turn(self, tau_Nm: np.ndarray) -> np.ndarray:
        """The joint's turn [rad] beyond its (identified) linear spring under the torques ``tau_Nm`` [N m]."""
        t = np.asarray(tau_Nm, float)
        return stiffening_turn(t, self.s_rad_per_Nm2, self.saturation_Nm) - self.linear_rad_per_Nm * t


class JointStiffening(CampaignEffectModel):
    effect = "joint_stiffening"
    order = 80
    params = (ParamSpec("joint", "-", "the joint (2-based: joint 1 carries no static torque about its axis)",
                        kind="int", magnitude=False),
              ParamSpec("stiffening_rad_per_Nm2", "rad/(N m)^2", "s: the joint's angle is c tau - s tau abs(tau) (s > 0: "
                                                               "stiffer under load)"),
              ParamSpec("saturation_Nm", "N m", "tau_s: the departure is divided by 1 + abs(tau) / tau_s (a spring that "
                                                "stiffens until nearly rigid; 0: none, the quadratic)", default=0.0,
                        magnitude=False))
    example = {"joint": 2, "stiffening_rad_per_Nm2": 3.0e-8}
    physics = "one joint's gear is a non-linear spring: its compliance changes with the torque it carries"
    signature = ("the residuals follow that joint's motion in proportion to tau abs(tau), the square of its static "
                 "torque with its sign, or to tau abs(tau) / (1 + abs(tau) / tau_s) for a spring that stiffens until "
                 "nearly rigid")
    locations = ("joint:K",)
    reported = ("`stiffening_rad_per_Nm2` [rad/(N m)^2], `saturation_Nm` [N m] when it saturates: joint K turns by "
                "`c tau - s tau abs(tau) / (1 + abs(tau) / tau_s)` under its torque")
    required = ("joint",)

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        self.check_joint(p, n_joints, 2, "joint 1 carries no static torque about its axis")
        if not float(p.get("saturation_Nm", 0.0)) >= 0:
            self.fail(f"effect {self.effect}: saturation_Nm must be >= 0 N m (0: no saturation), got "
                      f"{p['saturation_Nm']}",
                      f"{self.effect}.saturation_Nm")

    def torque_angles(self, q_rad: np.ndarray, tau_Nm: np.ndarray, p: dict) -> np.ndarray:
        k = int(p["joint"]) - 1
        out = np.array(q_rad, float, copy=True)
        out[:, k] += stiffening_turn(tau_Nm[:, k], float(p["stiffening_rad_per_Nm2"]), p.get("saturation_Nm"))
        return out

    def hypotheses(self, ctx: CampaignContext) -> list:
        if ctx.tau_Nm is None:
            return []
        fr, N, out = ctx.frames, ctx.n_points, []
        for k in range(1, ctx.robot.n):
            t = ctx.tau_Nm[:, k]
            if np.ptp(t) < MIN_TORQUE_SPAN_NM:
                continue
            g = joint_motion_W(fr, k)
            top = float(np.max(np.abs(t)))
            for sat in (None,) + tuple(round(top * f, 1) for f in SATURATION_GRID):
                H = (g * stiffening_turn(t, 1.0, sat)[:, None]).reshape(3 * N, 1)
                how = "" if sat is None else f", saturating above ~{sat:.3g} N m"
                out.append(hypothesis(self.effect, f"joint:{k + 1}", ["stiffening_rad_per_Nm2"], H,
                                      f"joint {k + 1}'s gear is a non-linear spring: its compliance changes with the "
                                      f"torque it carries ({np.min(t):.0f}..{np.max(t):.0f} N m here{how})",
                                      **({} if sat is None else {"hidden": 1, "settings": {"saturation_Nm": sat}})))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        k = int(location_parts(location)[1]) - 1
        correction = TorqueCorrection.over(ctx.tau_Nm[:, k], parameters["stiffening_rad_per_Nm2"],
                                           parameters.get("saturation_Nm") or None, fit.torque_linear_to_c)
        shift = np.zeros_like(ctx.obs.q_rad)
        shift[:, k] = correction.turn(ctx.tau_Nm[:, k])
        fit.obs_edits.append(lambda obs: replace(obs, q_rad=obs.q_rad + shift))
        fit.torque_corrections[k] = correction

    def remedy(self, location: str, parameters: dict) -> str:
        j = location_parts(location)[1]
        return (f"joint {j}'s stiffness changes with its load: identify its compliance over the torques it works at "
                f"(a load test of joint {j}), or calibrate with the robot loaded as in use; the linear c_{j} is an "
                "average over this campaign's torques")
