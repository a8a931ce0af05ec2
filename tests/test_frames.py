"""The contract's pose convention: R = Rx(a) Ry(b) Rz(c), moving axes."""
from __future__ import annotations

import numpy as np

from rodlab.core.frames import matrix_to_pose, pose_to_matrix, rot_x, rot_y, rot_z


def test_order_and_round_trip():
    rng = np.random.default_rng(0)
    poses = np.column_stack([rng.uniform(-500, 500, (50, 3)), rng.uniform(-170, 170, (50, 1)),
                             rng.uniform(-89, 89, (50, 1)), rng.uniform(-170, 170, (50, 1))])
    T = pose_to_matrix(poses)
    a, b, c = np.deg2rad(poses[7, 3:])
    np.testing.assert_allclose(T[7, :3, :3], rot_x(a) @ rot_y(b) @ rot_z(c), atol=1e-12)
    np.testing.assert_allclose(T[7, :3, 3], poses[7, :3])
    np.testing.assert_allclose(matrix_to_pose(T), poses, atol=1e-9)
    R = T[:, :3, :3]
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.broadcast_to(np.eye(3), R.shape), atol=1e-12)


def test_gimbal_lock_round_trip():
    T = pose_to_matrix([1, 2, 3, 30.0, 90.0, 0.0])
    np.testing.assert_allclose(pose_to_matrix(matrix_to_pose(T)), T, atol=1e-9)


def test_moving_axes_example():
    # rotate 90 deg about x, then about the new y: the new y is the old z
    R = pose_to_matrix([0, 0, 0, 90.0, 90.0, 0.0])[:3, :3]
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-12)
