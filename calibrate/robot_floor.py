"""The robot's own unmodelled error (:class:`RobotFloor`): smooth joint-angle errors outside the calibration model
that the simulator adds to its truth robot and the study's predictors add to their campaigns
(``priors.robot_floor_mm``; :mod:`calibrate.unmodelled`), sized by the mean position error they give."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import CalibrationError
from .kinematics import ModelParams, ball_positions

__all__ = ["RobotFloor", "robot_floor", "FLOOR_HARMONICS", "FLOOR_TOOL_MM", "FLOOR_POSES"]


#: harmonics of a joint's own angle in the robot floor (gear transmission, cyclic errors); the first is left out:
#: the identified joint offsets and link lengths absorb most of it
FLOOR_HARMONICS = (2, 3)
#: rigid validation tool and poses the floor is sized on (as the study's validation: 150 mm, 60 % of the limits)
FLOOR_TOOL_MM = (0.0, 0.0, 150.0)
FLOOR_POSES = 400


@dataclass(frozen=True)
class RobotFloor:
    """The robot's own unmodelled error: smooth joint-angle errors outside the calibration model.

    ``q_true = q + sum_k a_ik sin(k q_i + phi_ik) + b_i cos(2 s_i)`` per joint i: harmonics ``FLOOR_HARMONICS``
    of the joint's own angle (gear transmission and cyclic errors) and, for joints 2 and 3, a link-deflection
    term in the angle of the arm to the vertical (``s_2 = q_2``, ``s_3 = q_2 + q_3``; cos 2s, not the gravity
    torque the model's joint compliance absorbs).

    amp_rad : a, shape=(n, len(FLOOR_HARMONICS)) [rad]; phase_rad : phi, same shape [rad]; sag_rad : b, shape=(n,)
    [rad]; floor_mm : the mean position error of a rigid 150 mm tool these errors give on random poses [mm]
    """

    amp_rad: np.ndarray
    phase_rad: np.ndarray
    sag_rad: np.ndarray
    floor_mm: float

    def __post_init__(self) -> None:
        n = np.shape(self.sag_rad)[0]
        for key in ("amp_rad", "phase_rad"):
            if np.shape(getattr(self, key)) != (n, len(FLOOR_HARMONICS)):
                raise CalibrationError(f"expected shape ({n}, {len(FLOOR_HARMONICS)}), got "
                                       f"{np.shape(getattr(self, key))}", key=key)

    def angles(self, q_rad: np.ndarray) -> np.ndarray:
        """The angles the joints really take at commanded ``q_rad`` (N, n) [rad]."""
        q = np.atleast_2d(np.asarray(q_rad, float))
        k = np.asarray(FLOOR_HARMONICS, float)
        e = np.sum(self.amp_rad * np.sin(q[:, :, None] * k + self.phase_rad), axis=2)
        arm = np.zeros_like(q)
        if q.shape[1] >= 3:
            arm[:, 1], arm[:, 2] = q[:, 1], q[:, 1] + q[:, 2]
        return q + e + self.sag_rad * np.cos(2.0 * arm)


def _floor_mean_mm(robot, floor: RobotFloor, q: np.ndarray) -> float:
    nominal = ModelParams.nominal(robot, np.asarray(FLOOR_TOOL_MM, float))
    p0, _ = ball_positions(robot, nominal, q)
    p1, _ = ball_positions(robot, nominal, floor.angles(q))
    return float(np.mean(np.linalg.norm(p1.pW - p0.pW, axis=1)))


def robot_floor(robot, floor_mm: float, seed: int) -> RobotFloor | None:
    """A random :class:`RobotFloor` of the robot, scaled so that its mean position error on a rigid 150 mm tool
    over random poses within 60 % of the joint limits is ``floor_mm`` (``None`` at 0). Drawn from a generator of
    its own (``seed``), so the other draws of a simulation stay those without it. The calibration absorbs
    little of it (harmonics >= 2, cos 2s are outside the kinematic and joint-compliance model): calibrated with
    a perfect instrument the robot ends near ``floor_mm``, as the paper's laser-scanner calibration did."""
    if not np.isfinite(floor_mm) or floor_mm < 0:
        raise CalibrationError(f"must be a finite number >= 0, got {floor_mm!r}", key="robot_floor_mm")
    if floor_mm == 0:
        return None
    rng = np.random.default_rng([int(seed), 45])
    n, h = robot.n, len(FLOOR_HARMONICS)
    unit = RobotFloor(rng.normal(0, 1e-4, (n, h)), rng.uniform(0, 2 * np.pi, (n, h)),
                      np.where(np.isin(np.arange(n), (1, 2)), rng.normal(0, 1e-4, n), 0.0), 0.0)
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    q = rng.uniform(lo * 0.6, hi * 0.6, (FLOOR_POSES, n))
    scale = floor_mm / _floor_mean_mm(robot, unit, q)
    out = RobotFloor(unit.amp_rad * scale, unit.phase_rad, unit.sag_rad * scale, float(floor_mm))
    scale *= floor_mm / _floor_mean_mm(robot, out, q)        # one correction for the small non-linearity
    return RobotFloor(unit.amp_rad * scale, unit.phase_rad, unit.sag_rad * scale, float(floor_mm))
