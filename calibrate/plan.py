"""Pose planning: choose the rod orientations at each clamping position that make the campaign most
observable (Borm & Menq's O1; O2-O5 of Sun & Hollerbach / Joubair et al. reported).

Candidates are reachable configurations that put the ball on each datum point (numeric IK from random
seeds within the joint limits); a greedy exchange picks ``k`` per position maximising O1 of the
column-scaled identification Jacobian of the free parameters.
"""
from __future__ import annotations

import numpy as np

from .identify import _select
from .errors import CalibrationError
from .ik import random_configurations, solve_ik_groups
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .params import catalogue
from .simulate import standard_base

__all__ = ["observability", "plan_poses"]


def observability(J: np.ndarray) -> dict:
    """O1..O5 of a column-scaled Jacobian, shape=(3N, P)."""
    Jn = J / np.maximum(np.linalg.norm(J, axis=0), 1e-300)
    s = np.linalg.svd(Jn, compute_uv=False)
    m = s.size
    n_rows = J.shape[0]
    return {"O1": float(np.exp(np.mean(np.log(np.maximum(s, 1e-300)))) / np.sqrt(n_rows)),
            "O2": float(s[-1] / s[0]), "O3": float(s[-1]), "O4": float(s[-1] ** 2 / s[0]),
            "O5": float(1.0 / np.sum(1.0 / np.maximum(s, 1e-300))), "condition": float(s[0] / max(s[-1], 1e-300)),
            "parameters": m}


def reachable_candidates(robot, params: ModelParams, fixture, k: int, candidates: int, rng, rod_mass_kg=0.0,
                         rod_com_T_mm=None) -> dict:
    """Up to ``candidates`` reachable configurations [rad] per clamping position (dict j -> (m, n) array):
    position IK from ``4 * candidates`` random seeds per position, every position in one batch."""
    m = 4 * candidates
    targets = {j: np.tile(fixture.transform(j)[:3, 3], (m, 1)) for j in fixture.poses}
    seeds = random_configurations(robot, rng, len(targets) * m)
    reached = solve_ik_groups(robot, params, targets, seeds, rod_mass_kg, rod_com_T_mm)
    cands = {}
    for j, got in reached.items():
        got = got[:candidates]
        if len(got) < k:
            raise CalibrationError(f"clamping position {j}: only {len(got)} of {m} tried rod orientations reach "
                                   f"the datum point, {k} needed; move the fixture within reach",
                                   key=f"positions.{j}")
        cands[j] = got
    return cands


def plan_poses(robot, fixture, tool_mm, k: int = 6, candidates: int = 30, seed: int = 0, rod_mass_kg: float = 0.0,
               rod_com_T_mm=None, base_guess=None):
    """Joint angles [deg] per clamping position (dict j -> (k, n) array) and the observability indices."""
    rng = np.random.default_rng(seed)
    p = ModelParams.nominal(robot, tool_mm, base=base_guess)
    if base_guess is None:
        p = p.with_(base=standard_base())      # {W} 650 mm in front, 250 mm up, device tilted as in the paper
    cands = reachable_candidates(robot, p, fixture, k, candidates, rng, rod_mass_kg, rod_com_T_mm)
    allq = np.concatenate(list(cands.values()))
    infos = catalogue(robot.n)
    fr, tau = ball_positions(robot, p, allq, rod_mass_kg, rod_com_T_mm)
    Jall = position_jacobian(fr, tau, infos, p.base)
    free, _ = _select(robot, tool_mm, infos, Jall, {}, set())
    Jall = Jall[:, :, free]
    chosen = {j: list(range(k)) for j in cands}
    offsets = {j: int(np.sum([len(cands[i]) for i in cands if i < j])) for j in cands}

    def J_of(ch):
        rows = [offsets[j] + i for j in ch for i in ch[j]]
        return Jall[rows].reshape(-1, len(free))
    best = observability(J_of(chosen))["O1"]
    for _ in range(3):                                      # greedy exchange passes
        improved = False
        for j in cands:
            for slot in range(k):
                for cand in range(len(cands[j])):
                    if cand in chosen[j]:
                        continue
                    trial = {jj: list(v) for jj, v in chosen.items()}
                    trial[j][slot] = cand
                    o = observability(J_of(trial))["O1"]
                    if o > best * (1 + 1e-9):
                        best, chosen, improved = o, trial, True
        if not improved:
            break
    out = {j: np.rad2deg(cands[j][chosen[j]]) for j in cands}
    return out, observability(J_of(chosen))
