"""Numeric pose inverse kinematics for many targets at once: joint angles that put the TCP frame on a pose.

Per target 6 equations (the TCP position [mm] and the orientation error, the rotation vector of
``R R_target^T`` [rad] weighted by :data:`ROTATION_WEIGHT_MM` so that 1 urad counts as 1 um) in n >= 6 unknowns
within the joint limits, solved for the whole batch by a projected Levenberg-Marquardt iteration as
:mod:`calibrate.ik` does for positions: one forward-kinematics call per iteration (joint compliance included in
the residual), the analytic Jacobian ``dp/dq_i = z_{i-1} x (p - o_{i-1})``, ``dw/dq_i = z_{i-1}``. Rows that do not
converge from their seed are restarted from a few random configurations (deterministic) and the solution
nearest the seed kept.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import CalibrationError
from .kinematics import ModelParams, ball_positions

__all__ = ["PoseIk", "solve_ik_poses", "tcp_poses", "rotation_angle", "ROTATION_WEIGHT_MM"]

#: weight of the orientation error against the position error [mm/rad]: 1 urad counts as 1 um
ROTATION_WEIGHT_MM = 1000.0
#: random restarts of rows that do not converge from their seed
RESTARTS = 8


@dataclass(frozen=True)
class PoseIk:
    """Result of :func:`solve_ik_poses`.

    q_rad : shape=(M, n) joint angles [rad] (the best iterate where ``ok`` is False); ok : shape=(M,) within
    both tolerances and the joint limits; error_mm : shape=(M,) TCP distance from the target [mm];
    error_rad : shape=(M,) angle between the TCP frame and the target orientation [rad]
    """

    q_rad: np.ndarray
    ok: np.ndarray
    error_mm: np.ndarray
    error_rad: np.ndarray


def rotation_angle(R) -> np.ndarray:
    """Angle [rad] of rotation matrices, shape=(..., 3, 3) -> (...); accurate for small angles too."""
    from scipy.spatial.transform import Rotation                        # heavy (scipy.spatial, ~0.35 s)
    R = np.asarray(R, float)
    return np.linalg.norm(Rotation.from_matrix(R.reshape(-1, 3, 3)).as_rotvec(), axis=1).reshape(R.shape[:-2])


def tcp_poses(robot, params: ModelParams, q_rad, R_tool=None) -> tuple[np.ndarray, np.ndarray]:
    """TCP positions [mm], shape=(M, 3), and orientations, shape=(M, 3, 3), in {W}: the tool point, and the
    flange frame {n} rotated by ``R_tool`` (the tool frame's orientation in {n}; identity by default)."""
    fr, _ = ball_positions(robot, params, np.atleast_2d(q_rad))
    R = np.einsum("ij,mjk->mik", fr.R_W0, fr.T[:, robot.n, :3, :3])
    return fr.pW, R if R_tool is None else R @ R_tool


def _residual(robot, params, q, p_t, R_t, R_tool):
    """Residuals, shape=(M, 6) ([mm] and weighted [rad]), and the Jacobian, shape=(M, 6, n)."""
    from scipy.spatial.transform import Rotation                        # heavy (scipy.spatial, ~0.35 s)
    fr, _ = ball_positions(robot, params, q)
    R = np.einsum("ij,mjk->mik", fr.R_W0, fr.T[:, robot.n, :3, :3]) @ R_tool
    w = Rotation.from_matrix(R @ np.swapaxes(R_t, 1, 2)).as_rotvec()
    r = np.concatenate([fr.pW - p_t, ROTATION_WEIGHT_MM * w], axis=1)
    Jp = np.einsum("ij,mkj->mik", fr.R_W0, np.cross(fr.z_prev, fr.p0[:, None, :] - fr.o_prev))
    Jw = np.einsum("ij,mkj->mik", fr.R_W0, fr.z_prev)
    return r, np.concatenate([Jp, ROTATION_WEIGHT_MM * Jw], axis=1)


@dataclass(frozen=True)
class _PoseBatch:
    """The problems one LM run solves: TCP targets in {W} [mm] (M, 3) and frames (M, 3, 3), the tool's rotation
    in {n} (3, 3), the joint limits [rad] (n,), the iterations allowed and the tolerances (position [mm],
    weighted rotation [mm])."""

    p_t: np.ndarray
    R_t: np.ndarray
    R_tool: np.ndarray
    lo: np.ndarray
    hi: np.ndarray
    iterations: int
    tol: np.ndarray

    def rows(self, rows) -> "_PoseBatch":
        """The same problems restricted to ``rows``."""
        return replace(self, p_t=self.p_t[rows], R_t=self.R_t[rows])


def _lm(robot, params, q0, batch: _PoseBatch):
    """Projected LM over the batch. Returns q and the final residuals, shape=(M, 6)."""
    M, n = q0.shape
    lo, hi, tol, R_tool = batch.lo, batch.hi, batch.tol, batch.R_tool
    q = np.clip(q0, lo, hi)
    r, J = _residual(robot, params, q, batch.p_t, batch.R_t, R_tool)
    cost = np.einsum("mi,mi->m", r, r)
    lam = np.full(M, 1e-3)
    active = ~_converged(r, tol)
    for _ in range(batch.iterations):
        a = np.nonzero(active)[0]
        if a.size == 0:
            break
        A = np.einsum("mik,mil->mkl", J[a], J[a])
        g = np.einsum("mik,mi->mk", J[a], r[a])
        H = A + (lam[a, None] * np.maximum(np.einsum("mkk->mk", A), 1e-9))[:, :, None] * np.eye(n)
        q_new = np.clip(q[a] - np.linalg.solve(H, g[..., None])[..., 0], lo, hi)
        r_new, J_new = _residual(robot, params, q_new, batch.p_t[a], batch.R_t[a], R_tool)
        c_new = np.einsum("mi,mi->m", r_new, r_new)
        better = c_new < cost[a]
        b = a[better]
        q[b], r[b], J[b], cost[b] = q_new[better], r_new[better], J_new[better], c_new[better]
        lam[a] = np.where(better, np.maximum(lam[a] / 3.0, 1e-12), np.minimum(lam[a] * 4.0, 1e8))
        active[a[_converged(r[a], tol) | (lam[a] >= 1e8)]] = False
    return q, r


def _converged(r: np.ndarray, tol: np.ndarray) -> np.ndarray:
    return (np.linalg.norm(r[:, :3], axis=1) < tol[0]) & (np.linalg.norm(r[:, 3:], axis=1) < tol[1])


def solve_ik_poses(robot, params: ModelParams, targets_mm, R_target, q_seed, R_tool=None, pos_tol_mm: float = 1e-5,
                   rot_tol_rad: float = 1e-8, iterations: int = 100, seed: int = 0) -> PoseIk:
    """Joint angles near ``q_seed`` [rad], shape=(M, n) or (n,), that put the TCP on ``targets_mm`` [mm],
    shape=(M, 3), with its frame at ``R_target``, shape=(M, 3, 3), both in {W} (see the module docstring)."""
    if robot.n < 6:
        raise CalibrationError(f"a pose target fixes 6 degrees of freedom; this robot has {robot.n} joints: give "
                               "position targets (x_mm, y_mm, z_mm only)", key="targets")
    p_t = np.atleast_2d(np.asarray(targets_mm, float))
    R_t = np.asarray(R_target, float).reshape(-1, 3, 3)
    M = len(p_t)
    seeds = np.broadcast_to(np.asarray(q_seed, float), (M, robot.n)).copy()
    R_tool = np.eye(3) if R_tool is None else np.asarray(R_tool, float)
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    tol = np.array([pos_tol_mm, ROTATION_WEIGHT_MM * rot_tol_rad])
    batch = _PoseBatch(p_t, R_t, R_tool, lo, hi, iterations, tol)
    q, r = _lm(robot, params, np.clip(seeds, lo + 1e-6, hi - 1e-6), batch)
    rng = np.random.default_rng(seed)
    for _ in range(RESTARTS):
        bad = np.nonzero(~_converged(r, tol))[0]
        if bad.size == 0:
            break
        start = rng.uniform(0.9 * lo, 0.9 * hi, (bad.size, robot.n))
        q2, r2 = _lm(robot, params, start, batch.rows(bad))
        take = np.linalg.norm(r2, axis=1) < np.linalg.norm(r[bad], axis=1)
        q[bad[take]], r[bad[take]] = q2[take], r2[take]
    ok = _converged(r, tol) & np.all((q >= lo) & (q <= hi), axis=1)
    return PoseIk(q, ok, np.linalg.norm(r[:, :3], axis=1), np.linalg.norm(r[:, 3:], axis=1) / ROTATION_WEIGHT_MM)
