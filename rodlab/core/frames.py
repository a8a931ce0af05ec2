"""Frames and the contract's pose convention.

A pose vector ``[x, y, z, a, b, c]`` (mm, deg) is a translation followed by the rotation
``R = Rx(a) @ Ry(b) @ Rz(c)`` (rotations about the moving axes, Staubli order). All functions
are vectorised over leading dimensions.
"""
from __future__ import annotations

import numpy as np

__all__ = ["rot_x", "rot_y", "rot_z", "pose_to_matrix", "matrix_to_pose", "rotation_from_abc", "skew",
           "abc_rate_axes"]


def skew(v) -> np.ndarray:
    """Skew matrices of vectors, shape (..., 3) -> (..., 3, 3), ``skew(a) @ b = a x b``."""
    v = np.asarray(v, dtype=float)
    z = np.zeros(v.shape[:-1])
    return np.stack([np.stack([z, -v[..., 2], v[..., 1]], -1),
                     np.stack([v[..., 2], z, -v[..., 0]], -1),
                     np.stack([-v[..., 1], v[..., 0], z], -1)], -2)


def _c_s(angle_rad):
    a = np.asarray(angle_rad, dtype=float)
    return np.cos(a), np.sin(a), a.shape


def rot_x(angle_rad) -> np.ndarray:
    """Rotation about x, shape=(..., 3, 3)."""
    c, s, sh = _c_s(angle_rad)
    o, z = np.ones(sh), np.zeros(sh)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def rot_y(angle_rad) -> np.ndarray:
    """Rotation about y, shape=(..., 3, 3)."""
    c, s, sh = _c_s(angle_rad)
    o, z = np.ones(sh), np.zeros(sh)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def rot_z(angle_rad) -> np.ndarray:
    """Rotation about z, shape=(..., 3, 3)."""
    c, s, sh = _c_s(angle_rad)
    o, z = np.ones(sh), np.zeros(sh)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def rotation_from_abc(abc_deg) -> np.ndarray:
    """``Rx(a) @ Ry(b) @ Rz(c)`` from angles [deg], shape=(..., 3) -> (..., 3, 3) (the product written out:
    one array fill instead of three stacked rotations, as the identification calls it thousands of times)."""
    abc = np.deg2rad(np.asarray(abc_deg, dtype=float))
    ca, cb, cc = np.cos(abc[..., 0]), np.cos(abc[..., 1]), np.cos(abc[..., 2])
    sa, sb, sc = np.sin(abc[..., 0]), np.sin(abc[..., 1]), np.sin(abc[..., 2])
    R = np.empty(abc.shape[:-1] + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = cb * cc, -cb * sc, sb
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = ca * sc + sa * sb * cc, ca * cc - sa * sb * sc, -sa * cb
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = sa * sc - ca * sb * cc, sa * cc + ca * sb * sc, ca * cb
    return R


def abc_rate_axes(R) -> np.ndarray:
    """World axes of the angle rates of ``R = Rx(a) Ry(b) Rz(c)``, shape=(..., 3, 3) -> (..., 3, 3): the rotation
    vector of small changes (da, db, dc) [rad] is ``E @ (da, db, dc)``, with columns ``x``, ``Rx(a) y`` and
    ``R z`` (how the uncertainty of recorded angles a, b, c becomes an uncertainty of the orientation). ``a`` is
    recovered from R as :func:`matrix_to_pose` does (b in [-90, 90] deg); for angles recorded with |b| > 90 deg
    the middle column changes sign, which leaves a covariance ``E S E^T`` unchanged."""
    R = np.asarray(R, dtype=float)
    a = np.arctan2(-R[..., 1, 2], R[..., 2, 2])
    E = np.zeros(R.shape[:-2] + (3, 3))
    E[..., 0, 0] = 1.0
    E[..., 1, 1], E[..., 2, 1] = np.cos(a), np.sin(a)
    E[..., :, 2] = R[..., :, 2]
    return E


def pose_to_matrix(pose) -> np.ndarray:
    """4x4 homogeneous matrix ``T(pose)`` of pose vectors [mm, deg], shape=(..., 6) -> (..., 4, 4)."""
    p = np.asarray(pose, dtype=float)
    if p.shape[-1] != 6:
        raise ValueError(f"a pose vector has 6 entries [x, y, z, a, b, c], got shape {p.shape}")
    T = np.zeros(p.shape[:-1] + (4, 4))
    T[..., :3, :3] = rotation_from_abc(p[..., 3:])
    T[..., :3, 3] = p[..., :3]
    T[..., 3, 3] = 1.0
    return T


def matrix_to_pose(T) -> np.ndarray:
    """Inverse of :func:`pose_to_matrix`, shape=(..., 4, 4) -> (..., 6) [mm, deg]; ``b`` in [-90, 90]."""
    T = np.asarray(T, dtype=float)
    R = T[..., :3, :3]
    # R = Rx(a) Ry(b) Rz(c): R[0,2] = sin b, R[1,2] = -sin a cos b, R[2,2] = cos a cos b,
    # R[0,0] = cos b cos c, R[0,1] = -cos b sin c
    b = np.arcsin(np.clip(R[..., 0, 2], -1.0, 1.0))
    a = np.arctan2(-R[..., 1, 2], R[..., 2, 2])
    c = np.arctan2(-R[..., 0, 1], R[..., 0, 0])
    gimbal = np.abs(np.cos(b)) < 1e-9
    if np.any(gimbal):  # c := 0, a from the remaining block
        a = np.where(gimbal, np.arctan2(R[..., 2, 1], R[..., 1, 1]), a)
        c = np.where(gimbal, 0.0, c)
    return np.concatenate([T[..., :3, 3], np.rad2deg(np.stack([a, b, c], -1))], -1)
