"""What every campaign effect provides: its parameter schema, its part of the campaign simulator (the truth),
its hypotheses for the diagnosis, how a finding is carried into the re-identification, its wording and its
remedy. One subclass per effect, one module each.

Simulator hooks, each applied by every active effect in registry order (:func:`rodlab.calibrate.simulate_campaign`):

1. ``true_rod`` — the rod as it really is (the compliance file the calibrator is given stays the nominal one);
2. ``joint_angles`` — the angles the joints really take for the commanded ones (campaign and validation);
   ``torque_angles`` — and, at a campaign's points, what their static torques add beyond the linear springs;
3. ``reading_offset_W`` — an offset of the measured ball position in {W} that grows with the campaign's time;
4. ``recorded_fixture`` — the clamping pose as the fixture file records it;
5. ``corrupt`` — gross errors of single readings in {D}, drawn from a generator of their own.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rodlab.core.hypothesis import EffectSchema, Hypothesis

from ..errors import CalibrationError

if TYPE_CHECKING:                       # the registry builds the Enum from the effect modules
    from . import CampaignEffect

__all__ = ["CampaignEffectModel", "CampaignContext", "Refit", "hypothesis", "joint_motion_W"]


@dataclass(frozen=True)
class CampaignContext:
    """What campaign hypotheses are built from: the identified model and the campaign it was fitted to.

    robot : the robot model; result : the identification (:class:`~rodlab.calibrate.CalibrationResult`);
    obs : its observations (:class:`~rodlab.calibrate.identify.Observations`, {W} [mm], [rad], [N]);
    position : shape=(N,) clamping position of each point; labels : N point labels ``position.point``;
    time_s, temp_C : shape=(N,) or None, the campaign's time [s] and temperature [degC] columns;
    rod : the compliance file the campaign was calibrated with (None: no rod);
    frames : the identified model's ball-position frames at the campaign points
    (:func:`~rodlab.calibrate.kinematics.ball_positions`); tau_Nm : shape=(N, n), the joints' static torques there
    [N m], or None
    """

    robot: object
    result: object
    obs: object
    position: np.ndarray
    labels: list
    time_s: np.ndarray | None
    temp_C: np.ndarray | None
    rod: object
    frames: object
    tau_Nm: np.ndarray | None = None

    @property
    def n_points(self) -> int:
        return int(self.obs.x_W_mm.shape[0])


@dataclass
class Refit:
    """What the re-identification with the found physics takes from the findings.

    rod : the compliance file to compensate with; freed : parameter names freed (fixture offsets);
    keep : shape=(N,) bool, points kept (outliers dropped), required; joint_corrections_rad : {joint index (0-based):
    (a_sin, a_cos) [rad], or (a_sin, a_cos, b_sin, b_cos) with twice per revolution} periodic errors added to the
    joint angles (also at validation points);
    obs_edits : functions Observations -> Observations applied after the joint correction (e.g. measured
    points referred back to the campaign start); torque_corrections : {joint index (0-based):
    :class:`~rodlab.calibrate.effects.joint_stiffening.TorqueCorrection`} the joint's turn beyond its
    linear spring under its static torque (also at validation points, with their torques);
    torque_linear_to_c : a non-linear joint spring's part linear in the torque is left to the joint's compliance c
    (else applied with the rest)
    """

    rod: object
    keep: np.ndarray
    freed: set = field(default_factory=set)
    joint_corrections_rad: dict = field(default_factory=dict)
    obs_edits: list = field(default_factory=list)
    torque_corrections: dict = field(default_factory=dict)
    torque_linear_to_c: bool = False


def joint_motion_W(frames, k: int) -> np.ndarray:
    """How each ball centre moves per radian of joint ``k`` (0-based), in {W} [mm/rad], shape=(N, 3): the column
    through which an angle error of that joint shows in the residuals."""
    return np.cross(frames.z_prev[:, k], frames.p0 - frames.o_prev[:, k]) @ frames.R_W0.T


def hypothesis(effect, location, names, H, explanation, **kw) -> Hypothesis:
    """A campaign hypothesis: columns over the 3 N coordinates of the residual, fitted without bounds."""
    k = H.shape[1]
    return Hypothesis(effect, location, names, H, np.full(k, -np.inf), np.full(k, np.inf), explanation, **kw)


class CampaignEffectModel(EffectSchema):
    """One campaign effect. Subclasses set the class attributes and override the hooks they need.

    effect : its ID (the registry makes it its ``CampaignEffect`` member); order : its place in the registry (an
    int of its own: the simulator's order, and ties between equally good hypotheses go to the first); params : its
    simulator parameters (names and units shared with docs and CLI); example :
    the parameters ``--effect NAME`` gives when no magnitude is stated; physics : what is left out; signature :
    how it shows in the residuals; locations : its location keys in a diagnosis; reported : the parameters a
    finding reports (Markdown, for the docs table); per_point : its candidates are
    single points that do not use up the diagnosis' model terms (outliers)
    """

    effect: CampaignEffect     # written as its contract spelling, ``effect = "outliers"``
    order: int                 # e.g. ``order = 50``: where the simulator applies it and the diagnosis lists it
    physics: str = ""
    signature: str = ""
    locations: tuple = ()
    reported: str = ""
    per_point: bool = False
    required: tuple = ()        #: parameters that must be given whenever any is (where the effect is)
    repeatable: bool = False    #: may be simulated more than once (at different places)

    def complete(self, given: dict) -> dict:
        """As :meth:`EffectSchema.complete`; a parameter neither given nor defaulted takes the example's value,
        and a place (``required``) must be given with any other parameter."""
        given = dict(given)
        for name in self.required:
            if given and name not in given:
                self.fail(f"effect {self.effect}: give {name} with the other parameters (e.g. {name}="
                          f"{self.example.get(name)})", f"{self.effect}.{name}")
        if given:                 # a parameter neither given nor defaulted takes the example's value
            given = {**{k: v for k, v in self.example.items() if k not in given}, **given}
        out = super().complete(given)
        absent = [p.name for p in self.params if p.name not in out]
        if absent:
            self.fail(f"effect {self.effect}: no value for {absent}", f"{self.effect}.{absent[0]}")
        return out

    def same_place(self, p: dict, q: dict) -> bool:
        """Whether two repeats of a repeatable effect act at the same place."""
        return True

    def fail(self, message: str, key: str) -> None:
        raise CalibrationError(message, key=key)

    # -- simulator (identity unless overridden) -----------------------------------------------------------------
    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        """Fail if the parameters do not fit a campaign of ``positions`` clamping positions and ``points``
        points of a robot with ``n_joints`` joints (checked before anything is written)."""

    def check_joint(self, p: dict, n_joints: int, first: int = 1, why: str = "") -> None:
        """Fail unless ``p["joint"]`` is one of the robot's joints ``first``..``n_joints`` (``why``: the reason
        for a first joint other than 1)."""
        if first <= int(p["joint"]) <= n_joints:
            return
        if first == 1:
            self.fail(f"effect {self.effect}: joint {p['joint']} is not one of the robot's joints 1..{n_joints}",
                      f"{self.effect}.joint")
        self.fail(f"effect {self.effect}: joint {p['joint']} must be one of joints {first}..{n_joints} ({why})",
                  f"{self.effect}.joint")

    def true_rod(self, rod, p: dict):
        return rod

    def joint_angles(self, q_rad: np.ndarray, p: dict) -> np.ndarray:
        return q_rad

    def position_angles(self, q_rad: np.ndarray, j: int, p: dict) -> np.ndarray:
        """The angles ``q_rad`` (m, n) [rad] the joints really take at clamping position ``j`` (an offset of that
        position alone)."""
        return q_rad

    def torque_angles(self, q_rad: np.ndarray, tau_Nm: np.ndarray, p: dict) -> np.ndarray:
        """The angles ``q_rad`` (m, n) [rad] with what the static torques ``tau_Nm`` (m, n) [N m] add beyond the
        joints' linear springs (the model's ``c tau``)."""
        return q_rad

    def reading_offset_W(self, frames, time_s: np.ndarray, p: dict):
        """Offset [mm] in {W}, shape=(m, 3), of the measured points at times ``time_s`` (``frames``: the true
        robot's :class:`~rodlab.calibrate.kinematics.Frames` of those points), or None."""
        return None

    def recorded_fixture(self, j: int, pose: np.ndarray, p: dict) -> np.ndarray:
        return pose

    def corrupt(self, xD: np.ndarray, labels: list, rng: np.random.Generator, p: dict) -> tuple[np.ndarray, dict]:
        """Readings (N, 3) in {D} with gross errors, and what was done (for the truth file)."""
        return xD, {}

    def truth(self, p: dict | None) -> dict:
        """Keys this effect adds to ``truth.json`` besides its parameters (older truth keys); ``p`` None: the
        values when the effect is not simulated."""
        return {}

    # -- diagnosis ------------------------------------------------------------------------------------------------
    def hypotheses(self, ctx: CampaignContext) -> list[Hypothesis]:
        """Candidate terms of this effect for the identified campaign ``ctx``."""
        return []

    def point_hypothesis(self, i: int, ctx: CampaignContext) -> Hypothesis | None:
        """per_point effects: the candidate at point ``i`` (columns not whitened)."""
        return None

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        """Carry a finding (its location and reported parameters) into the re-identification ``fit``."""

    def remedy(self, location: str, parameters: dict) -> str:
        """One sentence: what to do about a finding of this effect."""
        return f"see docs/diagnose.md for {self.effect}"
