"""The simulated MultiCal set-up: where the device's clamping positions are around the robot (the simulator's,
the planner's and the study's set-up when no fixture file is given) and the simulated device's contact force."""
from __future__ import annotations

import numpy as np

from rodlab.core.frames import matrix_to_pose, rotation_from_abc

from .campaign import Fixture

__all__ = ["standard_base", "fixture_layout", "standard_fixture", "WORLD_IN_BASE_MM", "DEVICE_TILT_ABC_DEG",
           "CONTACT_FORCE_D_N"]


#: {W} (the world clamping position's device frame) in the robot base {0}: 650 mm in front, 250 mm up [mm]
WORLD_IN_BASE_MM = np.array([650.0, 0.0, 250.0])
#: the device frames' tilt (ABC [deg]): Rx(-45) Ry(35.26), so z_D lies along (1, 1, 1)/sqrt(3), up
DEVICE_TILT_ABC_DEG = np.array([-45.0, 35.26438968, 0.0])
#: the sensors' contact force in {D_j} [N] of the simulated device
CONTACT_FORCE_D_N = np.array([1.10, 1.25, 1.05])


def standard_base(distance_mm: float | None = None) -> np.ndarray:
    """Pose of the robot base {0} in {W} [mm, deg], shape=(6,): {W} 650 mm (or ``distance_mm``) in front of the
    robot, 250 mm up, the device frame tilted 54.7 deg (axes up at equal angles) — the simulator's and the planner's
    setup."""
    return matrix_to_pose(_base_in_world(distance_mm))


def _base_in_world(distance_mm: float | None = None) -> np.ndarray:
    T_base_W = np.eye(4)
    T_base_W[:3, :3] = rotation_from_abc(DEVICE_TILT_ABC_DEG)
    T_base_W[:3, 3] = WORLD_IN_BASE_MM if distance_mm is None else [float(distance_mm), *WORLD_IN_BASE_MM[1:]]
    return np.linalg.inv(T_base_W)


def fixture_layout(positions: int, rng) -> tuple[int, dict]:
    """The simulator's clamping positions: (the world position, {j: pose of {D_j} in {W}, 4 x 4}); the positions
    on an ellipse 150 x 180 mm around {W} (80 mm up and down), each device turned by a random yaw (+-60 deg)."""
    R_WD = rotation_from_abc(DEVICE_TILT_ABC_DEG)
    T_W_base = _base_in_world()
    wp = 1 + positions // 2
    Ts = {}
    for j in range(1, positions + 1):
        if j == wp:
            Ts[j] = np.eye(4)
            continue
        ang = 2 * np.pi * (j - 1) / max(positions - 1, 1)
        off_base = np.array([150 * np.cos(ang), 180 * np.sin(ang), 80 * np.sin(2 * ang)])
        yaw = rng.uniform(-60, 60)
        Tb = np.eye(4)
        Tb[:3, :3] = rotation_from_abc([0, 0, yaw]) @ R_WD
        Tb[:3, 3] = WORLD_IN_BASE_MM + off_base
        Ts[j] = T_W_base @ Tb
    return wp, Ts


def standard_fixture(positions: int = 5, seed: int = 0) -> Fixture:
    """A fixture of the simulator's layout (:func:`fixture_layout`), poses exact, for planning and studies
    without a fixture file."""
    wp, Ts = fixture_layout(positions, np.random.default_rng(seed))
    return Fixture({j: matrix_to_pose(T) for j, T in Ts.items()}, CONTACT_FORCE_D_N.copy(), wp)
