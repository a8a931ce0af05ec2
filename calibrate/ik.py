"""Numeric inverse kinematics for many configurations at once: joint angles that put the ball at a point.

The ball position is what MultiCal constrains (the orientation of the rod is free), so the problem per
configuration is 3 equations in n unknowns within the joint limits. All configurations are solved together by
a projected Levenberg-Marquardt iteration: one forward-kinematics call over the whole batch per iteration
(:func:`calibrate.kinematics.ball_positions`, vectorised), the analytic position Jacobian
``dp/dq_i = z_{i-1} x (p - o_{i-1})`` and an n x n solve per configuration. Two stages, as a planner wants:

1. pulled towards a seed configuration (``|p - target|^2 + w^2 |q - q_seed|^2``): different seeds give
   different rod orientations;
2. the position alone, started from stage 1, to ``pos_tol_mm``.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .errors import CalibrationError
from .kinematics import ModelParams, ball_positions
from .rod import Rod

__all__ = ["PLAN_PULL_ITERATIONS", "IkBatch", "solve_ik_positions", "solve_ik_position", "solve_ik_groups",
           "random_configurations"]

#: weight of the pull towards the seed in stage 1 [mm/rad]
SEED_WEIGHT = 5.0
#: stage 1's iterations for a planner (``pull_iterations``): its minimum is off the target by design (the pull),
#: it only has to come near the target near the seed, and the rows that creep there (a weak pull along the
#: robot's redundant directions) gain nothing from more: stage 2 finishes them. 600 seeds on the TX90, UR5, UR10
#: and R-2000iC: 15 iterations reach as many targets as 60 (+-1 %) in 0.06 s instead of 0.15 s
PLAN_PULL_ITERATIONS = 15


@dataclass(frozen=True)
class IkBatch:
    """Result of :func:`solve_ik_positions`.

    q_rad : joint angles [rad], shape=(M, n) (the last iterate where ``ok`` is False);
    ok : bool, shape=(M,): the ball is within ``pos_tol_mm`` of its target and the angles within the limits;
    error_mm : distance of the ball from its target [mm], shape=(M,); iterations : LM iterations run
    """

    q_rad: np.ndarray
    ok: np.ndarray
    error_mm: np.ndarray
    iterations: int


@dataclass(frozen=True)
class _Batch:
    """The problems one LM run solves: ball targets in {W} [mm] (M, 3); the rod (its weight) and the contact
    forces in {W} [N] (M, 3) or None, which deflect the compliant joints; the joint limits [rad] (n,); the
    iterations allowed and the position tolerance [mm]."""

    targets: np.ndarray
    rod: Rod | None
    force_W_N: np.ndarray | None
    lo: np.ndarray
    hi: np.ndarray
    iterations: int
    tol_mm: float

    def rows(self, rows) -> "_Batch":
        """The same problems restricted to ``rows``."""
        return replace(self, targets=self.targets[rows],
                       force_W_N=None if self.force_W_N is None else self.force_W_N[rows])


def _residual_and_jacobian(robot, params: ModelParams, q, batch: _Batch):
    """Ball position error [mm], shape=(M, 3), and its Jacobian in {W} [mm/rad], shape=(M, 3, n) (the joint
    compliance's own dependence on q is neglected in the Jacobian, not in the residual)."""
    fr, _ = ball_positions(robot, params, q, batch.rod, force_W_N=batch.force_W_N)
    targets = batch.targets
    r = fr.pW - targets
    J0 = np.cross(fr.z_prev, fr.p0[:, None, :] - fr.o_prev)            # (M, n, 3) in {0}
    J = np.einsum("ij,mkj->mik", fr.R_W0, J0)                           # (M, 3, n) in {W}
    return r, J


def _lm(robot, params, q0, batch: _Batch, q_pull=None, weight: float = 0.0):
    """Projected LM over the batch, pulled towards ``q_pull`` with ``weight`` [mm/rad] (None: position only).
    Returns q, |r|, iterations run."""
    M, n = q0.shape
    lo, hi, iterations, tol = batch.lo, batch.hi, batch.iterations, batch.tol_mm
    q = np.clip(q0, lo, hi)
    lam = np.full(M, 1e-3)
    eye = np.eye(n)

    def cost_parts(qq, rows=slice(None)):
        r, J = _residual_and_jacobian(robot, params, qq, batch.rows(rows))
        c = np.einsum("mi,mi->m", r, r)
        if q_pull is not None:
            dq = qq - q_pull[rows]
            c = c + weight ** 2 * np.einsum("mi,mi->m", dq, dq)
        return r, J, c
    r, J, cost = cost_parts(q)
    active = np.ones(M, dtype=bool)
    it = 0
    for it in range(1, iterations + 1):
        a = np.nonzero(active)[0]                     # converged rows are left as they are: only these move
        Ja, ra = J[a], r[a]
        A = np.einsum("mik,mil->mkl", Ja, Ja)
        g = np.einsum("mik,mi->mk", Ja, ra)
        if q_pull is not None:
            A = A + weight ** 2 * eye
            g = g + weight ** 2 * (q[a] - q_pull[a])
        diag = np.einsum("mkk->mk", A)
        H = A + (lam[a, None] * np.maximum(diag, 1e-9))[:, :, None] * eye
        step = -np.linalg.solve(H, g[..., None])[..., 0]
        q_new = np.clip(q[a] + step, lo, hi)
        r_new, J_new, cost_new = cost_parts(q_new, a)
        ok = cost_new < cost[a]
        b = a[ok]
        q[b], r[b], J[b], cost[b] = q_new[ok], r_new[ok], J_new[ok], cost_new[ok]
        lam[a] = np.where(ok, np.maximum(lam[a] / 3.0, 1e-12), np.minimum(lam[a] * 4.0, 1e8))
        err = np.linalg.norm(r[a], axis=1)
        small = np.abs(step).max(axis=1) < 1e-12
        done = (err < tol) if q_pull is None else (small & ok) | (lam[a] >= 1e8)
        active[a[done | (lam[a] >= 1e8)]] = False
        if not active.any():
            break
    return q, np.linalg.norm(r, axis=1), it


def solve_ik_positions(robot, params: ModelParams, targets_W, q_seed, rod: Rod | None = None, force_W_N=None, *,
                       pos_tol_mm: float = 1e-4, iterations: int = 60, pull: bool = True,
                       pull_iterations: int | None = None, margin_deg: float = 0.0) -> IkBatch:
    """Joint angles near ``q_seed`` [rad], shape=(M, n), that put the ball at ``targets_W`` [mm], shape=(M, 3)
    or (3,), with the weight of ``rod`` (:class:`~rodlab.calibrate.rod.Rod` or None) and a contact force
    ``force_W_N`` [N] ((M, 3), (3,) or None) deflecting the compliant joints of ``params``. All M problems are
    solved together (see the module docstring). ``pull=False`` skips stage 1, for seeds already near a solution
    (planned configurations); ``pull_iterations`` caps it (None: ``iterations``; a planner that tries many seeds:
    :data:`PLAN_PULL_ITERATIONS`); ``margin_deg``: solve within the limits narrowed by this much at each end (a
    planner's configurations stay off the hard limits)."""
    q_seed = np.atleast_2d(np.asarray(q_seed, float))
    M, n = q_seed.shape
    if n != robot.n:
        raise CalibrationError(f"q_seed has {n} joints per row, the robot has {robot.n}", key="q_seed")
    targets = np.broadcast_to(np.asarray(targets_W, float), (M, 3))
    force = None if force_W_N is None else np.broadcast_to(np.asarray(force_W_N, float), (M, 3))
    lo, hi = np.deg2rad(robot.limits_deg[:, 0] + margin_deg), np.deg2rad(robot.limits_deg[:, 1] - margin_deg)
    if np.any(lo >= hi):
        raise CalibrationError(f"margin_deg {margin_deg:g} leaves no range of some joint's limits", key="margin_deg")
    if pull_iterations is not None and pull_iterations < 1:
        raise CalibrationError(f"pull_iterations must be >= 1, got {pull_iterations}; to skip the pull towards "
                               f"the seeds give pull=False", key="pull_iterations")
    batch = _Batch(targets, rod, force, lo, hi, iterations, pos_tol_mm)
    seed = np.clip(q_seed, lo + 1e-6, hi - 1e-6)
    q, it1 = seed, 0
    if pull:
        stage1 = replace(batch, iterations=iterations if pull_iterations is None else pull_iterations)
        q, _, it1 = _lm(robot, params, seed, stage1, seed, SEED_WEIGHT)
    q, err, it2 = _lm(robot, params, q, batch)
    ok = (err < pos_tol_mm) & np.all((q >= lo) & (q <= hi), axis=1)
    return IkBatch(q, ok, err, it1 + it2)


def solve_ik_position(robot, params: ModelParams, target_W, q_seed, rod: Rod | None = None, force_W_N=None, *,
                      pos_tol_mm: float = 1e-4):
    """One configuration: joint angles [rad], shape=(n,), near ``q_seed`` that put the ball at ``target_W``
    [mm], or None (see :func:`solve_ik_positions`)."""
    res = solve_ik_positions(robot, params, np.asarray(target_W, float)[None], np.asarray(q_seed, float)[None],
                             rod, None if force_W_N is None else np.atleast_2d(force_W_N), pos_tol_mm=pos_tol_mm)
    return res.q_rad[0] if res.ok[0] else None


def random_configurations(robot, rng, count: int, fraction: float = 0.7) -> np.ndarray:
    """``count`` joint configurations [rad], shape=(count, n), uniform within ``fraction`` of each joint's
    limits: the seeds from which the planner and the campaign simulator look for rod orientations."""
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    return rng.uniform(fraction * lo, fraction * hi, (count, robot.n))


def solve_ik_groups(robot, params: ModelParams, targets: dict, seeds: np.ndarray, rod: Rod | None = None,
                    forces: dict | None = None, pull_iterations: int | None = None, margin_deg: float = 0.0) -> dict:
    """Position IK of several groups of targets in one batch (a group: one clamping position).

    targets : {group: (m_g, 3) [mm]}; seeds : (sum m_g, n) [rad], in the groups' order; forces : {group: (3,)
    [N]} contact force of each group, or None; pull_iterations, margin_deg : as :func:`solve_ik_positions`'. Returns {group:
    the configurations that reached their target, (k_g, n) [rad], in seed order}."""
    keys = list(targets)
    sizes = [len(targets[j]) for j in keys]
    F = None if forces is None else np.repeat(np.array([forces[j] for j in keys]), sizes, axis=0)
    res = solve_ik_positions(robot, params, np.concatenate([targets[j] for j in keys]), seeds, rod, F,
                             pull_iterations=pull_iterations, margin_deg=margin_deg)
    edges = np.cumsum([0, *sizes])
    return {j: res.q_rad[a:b][res.ok[a:b]] for j, a, b in zip(keys, edges[:-1], edges[1:])}
