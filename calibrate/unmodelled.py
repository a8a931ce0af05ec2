"""What neither the calibration model nor any compensation describes, as the linear predictor draws it.

Two effects perturb a real campaign beyond the robot's modelled errors and the rod's elastic deflection, and
:mod:`calibrate.predict` (Monte Carlo) simulates both; the linear predictor (:mod:`calibrate.predict_linear`)
draws them here, per draw, as data offsets added to its linear model:

- the robot's own unmodelled error (:class:`~calibrate.robot_floor.RobotFloor`, ``priors.robot_floor_mm``): one
  floor per draw (seeds ``seed + d``, as Monte Carlo's replicates), the same in the campaign (at the planned
  poses, with the rod's lever) and on the validation points (projected off base and tool);
- the rod's non-repeatable deflection (:mod:`calibrate.rod_slip`, ``priors.rod_slip``) with each draw's true
  gravity compliance.
"""
from __future__ import annotations

import numpy as np

from .compensations.rod_deflection import flange_loads
from .kinematics import ModelParams, ball_positions
from .observations import Observations
from .rod import Rod
from .rod_slip import slip_directions
from .robot_floor import robot_floor

__all__ = ["cached_floor_draws", "campaign_offsets", "validation_floor_offsets"]

_FLOORS: dict = {}


def cached_floor_draws(robot, floor_mm: float, draws: int, seed: int = 0) -> list:
    """:func:`calibrate.robot_floor.robot_floor` of seeds ``seed .. seed + draws - 1``, kept for the process's next
    design (one robot and floor at a time)."""
    key = (repr(robot), float(floor_mm), int(draws), int(seed))
    if key not in _FLOORS:
        _FLOORS.clear()
        _FLOORS[key] = [robot_floor(robot, floor_mm, seed + d) for d in range(int(draws))]
    return _FLOORS[key]


def campaign_offsets(robot, model: ModelParams, obs: Observations, priors, true_C: np.ndarray, seed: int
                     ) -> np.ndarray:
    """(D, 3N) [mm] per draw, the campaign ``obs`` (planned poses on the linearisation ``model``) perturbed by
    the rod's slip (``true_C`` (D, 18): each draw's true ``C_F``, ``C_g`` row-major; directions from a generator
    of their own, ``[seed, 46]``) and by the robot floor at its poses (zero where ``priors`` have neither)."""
    D = true_C.shape[0]
    out = np.zeros((D, 3 * obs.q_rad.shape[0]))
    if priors.rod_slip:
        R_TW, _, _ = flange_loads(robot, model, obs.q_rad, obs.force_W_N, obs.rod)
        u = slip_directions(np.random.default_rng([seed, 46]), D * R_TW.shape[0]).reshape(D, -1, 3)
        Cg = true_C[:, 9:].reshape(D, 3, 3)
        out += priors.rod_slip * np.einsum("nij,djk,dnk->dni", R_TW, Cg, u).reshape(D, -1)
    if priors.robot_floor_mm > 0:
        N = obs.q_rad.shape[0]
        floors = cached_floor_draws(robot, priors.robot_floor_mm, D, seed)
        q = np.concatenate([obs.q_rad] + [fl.angles(obs.q_rad) for fl in floors])     # one batch: (1 + D) N
        F = np.tile(obs.force_W_N, (D + 1, 1))
        p, _ = ball_positions(robot, model, q, obs.rod, force_W_N=F)
        pW = p.pW.reshape(D + 1, N, 3)
        out += (pW[1:] - pW[:1]).reshape(D, -1)
    return out


def validation_floor_offsets(robot, model: ModelParams, q_rad: np.ndarray, rod: Rod, Q: np.ndarray, floor_mm: float,
                             seed: int) -> np.ndarray:
    """(D, 3M) [mm] the robot floor's offsets of the validation points ``q_rad`` (D, M, n) of the validation
    rod ``rod`` (``model``'s tool; its weight), one floor per draw (the campaign's), projected off the
    base / tool columns ``Q`` (D, 3M, 9) as the validation's refit takes them out."""
    D, M, n = q_rad.shape
    floors = cached_floor_draws(robot, floor_mm, D, seed)
    q1 = np.concatenate([fl.angles(q_rad[d]) for d, fl in enumerate(floors)])
    p0, _ = ball_positions(robot, model, q_rad.reshape(D * M, n), rod)
    p1, _ = ball_positions(robot, model, q1, rod)
    e = (p1.pW - p0.pW).reshape(D, 3 * M)
    return e - (Q @ (np.swapaxes(Q, 1, 2) @ e[:, :, None]))[:, :, 0]
