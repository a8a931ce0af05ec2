"""``periodic_joint_error``: gear or encoder eccentricity, an angle error once per revolution of one joint.

Three forms compete per joint: once per revolution (eccentricity, ``amp_sin_rad``, ``amp_cos_rad``), twice per
revolution (an elliptical gear or encoder disc, ``amp2_sin_rad``, ``amp2_cos_rad``) and both at once (a gear
with both, the four terms); the better fit by BIC is named (the two-term forms go first where they fit as well).
A twice-per-revolution error read as a once-per-revolution one had been "found" and made the validation worse; a
gear with both (an IRB 4600 trial's joint 4: 0.02 deg once and 0.008 deg twice per revolution) had been named
once per revolution with the rest left as "no structure" (26 um rms of a 3 um device).
"""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis, joint_motion_W

__all__ = ["PeriodicJointError", "correct_joints"]

_ONCE = ["amp_sin_rad", "amp_cos_rad"]
_TWICE = ["amp2_sin_rad", "amp2_cos_rad"]


def correct_joints(q_rad: np.ndarray, corr: dict) -> np.ndarray:
    """Joint angles [rad], shape=(N, n), with the fitted periodic errors {joint index: (a_sin, a_cos) of once per
    revolution, or (a_sin, a_cos, b_sin, b_cos) with twice per revolution's b [rad]} added: the angles the joints
    really take."""
    q = np.array(q_rad, float, copy=True)
    for k, amps in corr.items():
        for h in range(len(amps) // 2):                       # harmonic h + 1
            a_s, a_c = amps[2 * h], amps[2 * h + 1]
            q[:, k] = q[:, k] + a_s * np.sin((h + 1) * q_rad[:, k]) + a_c * np.cos((h + 1) * q_rad[:, k])
    return q


def _partial_period(q: np.ndarray, m: int) -> str:
    """A caution when the joint's readings ``q`` [rad] span less than one period of the ``m``-per-revolution term:
    there any smooth error of the joint (a stiffness that changes with the torque, a link's bending) fits too."""
    span = float(np.rad2deg(np.ptp(q)))
    if span >= 360.0 / m:
        return ""
    return (f" (caution: the joint turned over {span:.0f} deg only, less than one period of {360.0 / m:.0f} deg, so "
            "any smooth error of this joint fits as well; the amplitude holds over that range only)")


#: a joint turned over at least this much [deg] shows most of a once-per-revolution error's period
MOST_OF_A_TURN_DEG = 300.0

class PeriodicJointError(CampaignEffectModel):
    effect = "periodic_joint_error"
    order = 30
    params = (ParamSpec("joint", "-", "the joint (1-based)", kind="int", magnitude=False),
              ParamSpec("amp_deg", "deg", "amplitude A: the joint really turns q + A sin(q + phase)"),
              ParamSpec("phase_deg", "deg", "phase of the error", default=0.0, magnitude=False),
              ParamSpec("per_revolution", "-", "1: once per revolution (eccentricity), 2: twice (an elliptical "
                                               "gear or disc): q + A sin(m q + phase)", default=1, kind="int",
                        magnitude=False),
              ParamSpec("amp2_deg", "deg", "once per revolution only: a twice-per-revolution part besides, "
                                           "q + A sin(q + phase) + A2 sin(2 q + phase2)", default=0.0),
              ParamSpec("phase2_deg", "deg", "phase of the twice-per-revolution part", default=0.0, magnitude=False))
    example = {"joint": 4, "amp_deg": 0.006}
    physics = ("gear or encoder eccentricity (once per revolution) or an elliptical gear or disc (twice): the joint's "
               "angle is off by an error periodic in its reading")
    signature = "the residuals follow sin / cos of one joint's angle along that joint's motion"
    locations = ("joint:K",)
    reported = ("`amp_sin_rad`, `amp_cos_rad` [rad]: joint K turns `q + a_s sin q + a_c cos q`; or, twice per "
                "revolution, `amp2_sin_rad`, `amp2_cos_rad`: `q + b_s sin 2q + b_c cos 2q`; or all four (both)")

    required = ("joint",)

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        self.check_joint(p, n_joints)
        if int(p.get("per_revolution", 1)) not in (1, 2):
            self.fail(f"effect {self.effect}: per_revolution must be 1 or 2, got {p['per_revolution']}",
                      f"{self.effect}.per_revolution")
        if int(p.get("per_revolution", 1)) == 2 and float(p.get("amp2_deg", 0.0)):
            self.fail(f"effect {self.effect}: amp2_deg is the twice-per-revolution part of a once-per-revolution "
                      "error; with per_revolution=2 give the amplitude as amp_deg", f"{self.effect}.amp2_deg")

    def joint_angles(self, q_rad: np.ndarray, p: dict) -> np.ndarray:
        k, amp, ph = int(p["joint"]) - 1, np.deg2rad(p["amp_deg"]), np.deg2rad(p["phase_deg"])
        m = int(p.get("per_revolution", 1))
        amp2, ph2 = np.deg2rad(float(p.get("amp2_deg", 0.0))), np.deg2rad(float(p.get("phase2_deg", 0.0)))
        out = np.array(q_rad, float, copy=True)
        q = out[..., k].copy()
        out[..., k] += amp * np.sin(m * q + ph) + amp2 * np.sin(2 * q + ph2)
        return out

    def truth(self, p: dict | None) -> dict:
        return {"periodic_joint_error": None if p is None else [int(p["joint"]), float(p["amp_deg"]),
                                                                  float(p["phase_deg"]),
                                                                  int(p.get("per_revolution", 1))]}

    def hypotheses(self, ctx: CampaignContext) -> list:
        out = []
        modelled = ctx.result.harmonic_range_deg                 # joints the identification already carries
        for k in range(ctx.robot.n):
            if k + 1 not in modelled:
                out += self._joint_forms(ctx, k)
        return out

    def _joint_forms(self, ctx: CampaignContext, k: int) -> list:
        """The forms at joint ``k`` (0-based): once, twice, and once and twice per revolution where the joint
        turned a full revolution (over less, four terms fit any smooth error of the joint and extrapolate: an
        IRB 4600 trial's bending forearm read so at joint 3, 235 deg, made its validation 0.04 -> 0.12 mm)."""
        g, q, N = joint_motion_W(ctx.frames, k), ctx.obs.q_rad[:, k], ctx.n_points
        cols = {m: np.stack([g * np.sin(m * q)[:, None], g * np.cos(m * q)[:, None]], axis=-1).reshape(3 * N, 2)
                for m in (1, 2)}
        out = []
        for ms, names, what, times in (((1,), _ONCE, "gear or encoder eccentricity", "once"),
                                       ((2,), _TWICE, "an elliptical gear or encoder disc", "twice"),
                                       ((1, 2), _ONCE + _TWICE, "a gear or encoder disc both eccentric and "
                                                                "elliptical", "once and twice")):
            partial = _partial_period(q, min(ms))
            if len(ms) > 1 and partial:
                continue
            span = {"span_deg": round(float(np.rad2deg(np.ptp(q))), 1)} if _partial_period(q, 1) else {}
            limits = getattr(ctx.robot, "limits_deg", None)          # the joint's range, for the advice
            if span and limits is not None:
                span["range_deg"] = round(float(np.ptp(limits[k])), 1)
            out.append(hypothesis(self.effect, f"joint:{k + 1}", names, np.hstack([cols[m] for m in ms]),
                                  f"{what} of joint {k + 1}: an angle error {times} per revolution, periodic in q"
                                  + partial, form_unresolved=bool(partial), settings=span))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        k = int(location_parts(location)[1]) - 1
        once = (parameters.get("amp_sin_rad", 0.0), parameters.get("amp_cos_rad", 0.0))
        if "amp2_sin_rad" in parameters:
            fit.joint_corrections_rad[k] = once + (parameters["amp2_sin_rad"], parameters["amp2_cos_rad"])
        else:
            fit.joint_corrections_rad[k] = once

    def remedy(self, location: str, parameters: dict) -> str:
        j = location_parts(location)[1]
        twice = "amp2_sin_rad" in parameters
        times = ("once- and twice" if "amp_sin_rad" in parameters else "twice") if twice else "once"
        span = parameters.get("span_deg")
        if span is not None and MOST_OF_A_TURN_DEG <= span < 360.0 and not twice:
            return (f"joint {j} turned over {span:.0f} deg in this campaign, most of a revolution: a once-per-revolution "
                    f"error is told from a smooth one there, but not surely, and `--joint-harmonics {j}` fits four terms "
                    f"(once and twice per revolution), which over less than a turn may extrapolate: identify them and "
                    f"keep them only where validation points (--validate) show they help (a device trial: a real "
                    f"once-per-turn error over 340 deg took the validation from 0.119 to 0.036 mm; a bending forearm "
                    f"over 235 deg had made another one worse); or have the gearbox / encoder checked")
        if span is not None and span < 360.0:
            return (f"joint {j} turned over {span:.0f} deg only in this campaign, where a {times}-per-revolution error "
                    "cannot be told from any smooth error of the joint (a bending link, a gear that stiffens with "
                    f"the torque): do not identify it with `--joint-harmonics {j}` from this campaign (its four terms "
                    f"fit the campaign and extrapolate); {_wider(j, span, parameters.get('range_deg'))} and check the "
                    "result on validation points, or have the gearbox / encoder checked")
        return (f"joint {j} has a {times}-per-revolution angle error the kinematic model "
                "does not hold: have the gearbox / encoder checked, or identify it with the robot (add joint "
                f"{j} to `rodlab calibrate --joint-harmonics`) and compensate it in the "
                "controller")


def _wider(j: str, span: float, range_deg: float | None) -> str:
    """What campaign shows more of joint ``j``'s period: a full revolution where its limits allow one, else its
    whole range (a calibration engineer's trial: a full turn had been advised on a joint of 284 deg)."""
    if range_deg is None or range_deg >= 360.0:
        return f"record a campaign that turns joint {j} over a full revolution"
    if range_deg <= span + 10.0:
        return (f"the campaign already turns joint {j} over most of its {range_deg:.0f} deg range (a full revolution "
                "is beyond its limits): only validation points (--validate) can tell whether the terms help")
    return (f"record a campaign that turns joint {j} over its whole {range_deg:.0f} deg range (a full revolution is "
            "beyond its limits)")
