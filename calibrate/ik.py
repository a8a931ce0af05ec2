"""Numeric inverse kinematics: joint angles that put the ball at a point with a given rod orientation."""
from __future__ import annotations

import numpy as np

from .kinematics import ModelParams, ball_positions

__all__ = ["solve_ik"]


def _axis_angle(R):
    c = np.clip((np.trace(R) - 1) / 2, -1, 1)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = np.linalg.norm(w)
    ang = np.arccos(c)
    return w / s * ang if s > 1e-12 else np.zeros(3)


def solve_ik(robot, params: ModelParams, target_W, R_target_W, rng, starts: int = 12, rod_mass_kg=0.0,
             rod_com_T_mm=None, force_W_N=None, pos_tol_mm: float = 1e-4):
    """Joint angles [rad], shape=(n,), or None: ball at ``target_W`` [mm] and tool axes ``R_target_W``."""
    from scipy.optimize import least_squares
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])

    def fun(q):
        fr, _ = ball_positions(robot, params, q[None], rod_mass_kg, rod_com_T_mm,
                               None if force_W_N is None else np.atleast_2d(force_W_N))
        R = fr.R_W0 @ fr.T[0, robot.n, :3, :3]
        return np.concatenate([fr.pW[0] - target_W, 200.0 * _axis_angle(R_target_W.T @ R)])
    best = None
    for _ in range(starts):
        q0 = rng.uniform(lo * 0.8, hi * 0.8)
        r = least_squares(fun, q0, bounds=(lo, hi), xtol=1e-12, ftol=1e-12, max_nfev=400)
        if best is None or r.cost < best.cost:
            best = r
        if np.linalg.norm(r.fun[:3]) < pos_tol_mm and np.linalg.norm(r.fun[3:]) < 200 * 1e-6:
            return r.x
    if best is not None and np.linalg.norm(best.fun[:3]) < 10 * pos_tol_mm and np.linalg.norm(best.fun[3:]) < 200 * 1e-5:
        return best.x
    return None


def solve_ik_position(robot, params: ModelParams, target_W, q_seed, rod_mass_kg=0.0, rod_com_T_mm=None,
                      force_W_N=None, pos_tol_mm: float = 1e-4):
    """Joint angles [rad] near ``q_seed`` that put the ball at ``target_W`` (the orientation is free), or None."""
    from scipy.optimize import least_squares
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    q_seed = np.clip(q_seed, lo + 1e-6, hi - 1e-6)
    F = None if force_W_N is None else np.atleast_2d(force_W_N)

    def pos(q):
        return ball_positions(robot, params, q[None], rod_mass_kg, rod_com_T_mm, F)[0].pW[0] - target_W

    def jpos(q):                      # d p / d q_i = z_{i-1} x (p - o_{i-1}) (joint compliance neglected)
        fr = ball_positions(robot, params, q[None], rod_mass_kg, rod_com_T_mm, F)[0]
        return (np.cross(fr.z_prev[0], fr.p0[0] - fr.o_prev[0]) @ fr.R_W0.T).T

    r = least_squares(lambda q: np.concatenate([pos(q), 5.0 * (q - q_seed)]), q_seed, bounds=(lo, hi),
                      jac=lambda q: np.vstack([jpos(q), 5.0 * np.eye(q.size)]), max_nfev=100)
    r = least_squares(pos, r.x, jac=jpos, bounds=(lo, hi), xtol=1e-12, ftol=1e-12, max_nfev=100)
    if np.linalg.norm(r.fun) < pos_tol_mm:
        return r.x
    return None
