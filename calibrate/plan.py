"""Pose planning: choose the rod orientations at each clamping position that make the campaign most
observable (Borm & Menq's O1; O2-O5 of Sun & Hollerbach / Joubair et al. reported).

Candidates are reachable configurations that put the ball on each datum point (numeric IK from random
seeds within the joint limits) with the rod coming from the device's open side (within :data:`ROD_ANGLE_MAX_DEG`
of the diagonal its three sensor axes point along: the sensors sit below the ball and push it up); a greedy
exchange picks ``k`` per position maximising O1 of the column-scaled identification Jacobian of the free
parameters. The configurations reach the datum points of the robot standing where ``base`` says ({0} in {W}): a
calibration result's base, or a measured one; without it the standard layout (:func:`~calibrate.simulate.
standard_base`) is assumed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .estimate import Selection, select_free
from .errors import CalibrationError
from .ik import PLAN_PULL_ITERATIONS, random_configurations, solve_ik_groups
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions, forward
from .params import catalogue
from .rod import Rod
from .setup_layout import standard_base

__all__ = ["observability", "plan_poses", "rod_angle_deg", "above_floor", "Reach", "ROD_ANGLE_MAX_DEG", "L_ROD_EXIT",
           "LIMIT_MARGIN_DEG"]

#: the rod leaves the ball within this angle [deg] of its device's open diagonal ((1, 1, 1) / sqrt 3 in {D_j}); the
#: contract's example campaigns reach 124 deg (a rod nearly level passes beside the sensors), a rod pointing down
#: into the sensors (the new-user trial saw 142 deg) cannot be clamped
ROD_ANGLE_MAX_DEG = 125.0
#: the direction in {n} along which an L-shaped rod (gamma 90 deg) leaves its ball: back along pipe II
L_ROD_EXIT = (-1.0, 0.0, 0.0)
#: ``rodlab plan`` keeps every joint this far inside its limits [deg]: the IK projects onto the limits, and a pose on
#: a hard limit is one a controller stops short of (an IRB 4600 trial's plan had q3 = -170.0000 of [-170, 170],
#: q5 = -118 of [-118, 115] and q6 = 290 of [-290, 290])
LIMIT_MARGIN_DEG = 5.0
#: batches of random seeds a position short of candidates gets
SEED_ROUNDS = 3


@dataclass(frozen=True)
class Reach:
    """What a planned configuration must keep clear of.

    margin_deg : every joint at least this far inside its limits [deg] (0: the limits themselves);
    floor_mm : every joint's origin (shoulder, elbow, wrist) above this height [mm] in the robot's base frame {0},
        measured against the robot's gravity (the floor or a table under the robot: a DH frame {0} may sit at the
        shoulder or the floor, so only the user knows it), or None: no floor
    """

    margin_deg: float = 0.0
    floor_mm: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.margin_deg) and self.margin_deg >= 0):
            raise CalibrationError(f"the joint-limit margin must be >= 0 deg, got {self.margin_deg}", key="margin_deg")
        if self.floor_mm is not None and not np.isfinite(self.floor_mm):
            raise CalibrationError(f"the floor height must be a number of mm, got {self.floor_mm}", key="floor_mm")

    def words(self) -> str:
        out = (f"{self.margin_deg:g} deg inside every joint limit" if self.margin_deg > 0 else
               "within every joint limit")
        return out + (f" with every joint above {self.floor_mm:g} mm" if self.floor_mm is not None else "")


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


def reachable_candidates(robot, params: ModelParams, fixture, rod: Rod, k: int, candidates: int, rng,
                         max_rod_angle_deg: float | None = ROD_ANGLE_MAX_DEG, exit_n=L_ROD_EXIT,
                         reach: Reach = Reach()) -> dict:
    """Up to ``candidates`` reachable configurations [rad] per clamping position (dict j -> (m, n) array) of the
    robot ``params`` carrying ``rod``: position IK from ``4 * candidates`` random seeds per position, every
    position in one batch (its pull towards the seeds cut at :data:`~calibrate.ik.PLAN_PULL_ITERATIONS`), within
    the limits narrowed by ``reach.margin_deg``, kept where they clear the floor (:func:`above_floor`) and the rod
    comes from the device's open side; positions with fewer than ``k`` get up to :data:`SEED_ROUNDS` batches in all."""
    m = 4 * candidates
    found = {j: [] for j in fixture.poses}
    counts = {j: [0, 0] for j in fixture.poses}            # reached at all, of them above the floor
    for _ in range(SEED_ROUNDS):
        short = [j for j in found if sum(len(g) for g in found[j]) < (candidates if not found[j] else k)]
        if not short:
            break
        targets = {j: np.tile(fixture.transform(j)[:3, 3], (m, 1)) for j in short}
        seeds = random_configurations(robot, rng, len(targets) * m)
        reached = solve_ik_groups(robot, params, targets, seeds, rod, pull_iterations=PLAN_PULL_ITERATIONS,
                                  margin_deg=reach.margin_deg)
        for j, got in reached.items():
            counts[j][0] += len(got)
            if reach.floor_mm is not None:
                got = got[above_floor(robot, params, got, reach.floor_mm, rod)]
            counts[j][1] += len(got)
            if len(got) and max_rod_angle_deg is not None:
                got = got[rod_angle_deg(params, got, fixture.transform(j), exit_n) <= max_rod_angle_deg]
            found[j].append(got)
    return {j: _enough(j, np.concatenate(found[j])[:candidates], k, counts[j], m * SEED_ROUNDS, reach) for j in found}


def _enough(j, got: np.ndarray, k: int, counts: list, tried: int, reach: Reach) -> np.ndarray:
    """``got`` if it has at least ``k`` configurations, else the error saying where they were lost."""
    if len(got) >= k:
        return got
    raise CalibrationError(f"clamping position {j}: only {len(got)} of up to {tried} tried rod orientations reach the "
                           f"datum point from the device's open side ({counts[0]} reach it at all, {counts[1]} of them "
                           f"{reach.words()}), {k} needed; move the fixture within reach, or check the robot's base "
                           "pose (`rodlab plan --base`, `rodlab study --base` or `--fixture-distance-mm`), its joint "
                           "limits and the floor", key=f"positions.{j}")


def above_floor(robot, params: ModelParams, q_rad: np.ndarray, floor_mm: float, rod: Rod | None = None) -> np.ndarray:
    """Which configurations [rad] (M, n) keep every joint's origin (shoulder, elbow, wrist) above ``floor_mm``
    [mm], the height in {0} against the robot's gravity, shape=(M,) bool. (The joint-limit margin needs no check
    here: the IK solves within the narrowed limits.)"""
    fr, _ = ball_positions(robot, params, np.atleast_2d(q_rad), rod)
    up = -np.asarray(robot.gravity_base, float)
    height = fr.o_prev[:, 1:, :] @ (up / np.linalg.norm(up))          # frames 1..n-1: shoulder, elbow, wrist
    return np.all(height >= floor_mm, axis=1)


def rod_angle_deg(params: ModelParams, q_rad: np.ndarray, T_WD: np.ndarray, exit_n=L_ROD_EXIT) -> np.ndarray:
    """Angle [deg] between the rod as it leaves the ball (``exit_n``: unit vector in {n} from the ball back along
    pipe II, ``-RodDesign.pipe_II_direction``) and the open diagonal (1, 1, 1) / sqrt 3 of the device whose pose in
    {W} is ``T_WD``, shape=(N,)."""
    fr = forward(params, np.atleast_2d(q_rad))
    R_Wn = np.einsum("ij,njk->nik", fr.R_W0, fr.T[:, -1, :3, :3])
    exit_W = R_Wn @ (np.asarray(exit_n, float) / np.linalg.norm(exit_n))
    diag_W = np.asarray(T_WD, float)[:3, :3] @ (np.ones(3) / np.sqrt(3.0))
    return np.degrees(np.arccos(np.clip(exit_W @ diag_W, -1.0, 1.0)))


def plan_poses(robot, fixture, rod: Rod, k: int = 6, candidates: int = 30, seed: int = 0, base_guess=None,
               max_rod_angle_deg: float | None = ROD_ANGLE_MAX_DEG, exit_n=L_ROD_EXIT, reach: Reach = Reach()):
    """Joint angles [deg] per clamping position (dict j -> (k, n) array) and the observability indices, for the
    rod ``rod`` (:class:`~rodlab.calibrate.rod.Rod`: its tool vector and its weight; ``Rod.of(compliance)``);
    ``max_rod_angle_deg``: the rod leaves the ball within this angle of the device's open diagonal (None: any),
    along ``exit_n`` in {n} (:func:`rod_angle_deg`; an L-shaped rod's by default); ``reach``: the limit margin and
    floor the configurations keep clear of (:class:`Reach`; ``rodlab plan``: :data:`LIMIT_MARGIN_DEG`)."""
    if not isinstance(rod, Rod):
        raise TypeError(f"plan_poses takes the rod as a Rod (Rod.of(compliance) or Rod.rigid(tool_mm, mass_kg, "
                        f"com_T_mm)), got {type(rod).__name__}")
    rng = np.random.default_rng(seed)
    p = ModelParams.nominal(robot, rod.tool_mm, base=base_guess)
    if base_guess is None:
        p = p.with_(base=standard_base())      # {W} 650 mm in front, 250 mm up, device tilted as in the paper
    cands = reachable_candidates(robot, p, fixture, rod, k, candidates, rng, max_rod_angle_deg, exit_n, reach)
    allq = np.concatenate(list(cands.values()))
    infos = catalogue(robot.n)
    fr, tau = ball_positions(robot, p, allq, rod)
    Jall = position_jacobian(fr, tau, infos, p.base)
    free, _ = select_free(robot, Selection(infos, rod.tool_mm), Jall)
    Jall = Jall[:, :, free]
    chosen = {j: list(range(k)) for j in cands}
    offsets = {j: int(np.sum([len(cands[i]) for i in cands if i < j])) for j in cands}

    def J_of(ch):
        rows = [offsets[j] + i for j in ch for i in ch[j]]
        return Jall[rows].reshape(-1, len(free))
    chosen = _greedy_exchange(Jall, cands, chosen, offsets, k)
    out = {j: np.rad2deg(cands[j][chosen[j]]) for j in cands}
    return out, observability(J_of(chosen))


def _o1_of_gram(G: np.ndarray, rows: int) -> np.ndarray:
    """O1 of the column-scaled Jacobian from its Gram matrix ``G = J^T J`` (..., P, P): the singular values'
    geometric mean is ``det(D^-1 G D^-1)^(1/2P)``, ``D = sqrt(diag G)`` (the column scaling), / sqrt(rows)."""
    sign, logdet = np.linalg.slogdet(G)
    d = np.log(np.maximum(np.diagonal(G, axis1=-2, axis2=-1), 1e-300)).sum(axis=-1)
    return np.where(sign > 0, np.exp((logdet - d) / (2 * G.shape[-1])), 0.0) / np.sqrt(rows)


def _greedy_exchange(Jall: np.ndarray, cands: dict, chosen: dict, offsets: dict, k: int) -> dict:
    """Greedy exchange passes maximising O1: each slot of each position takes, in candidate order, any
    candidate that raises O1 by more than 1e-9 relative (the other slots' poses excluded). Every candidate of a
    slot is scored at once from the poses' Gram matrices (a swap changes ``J^T J`` by two 3-row terms)."""
    Gp = np.einsum("nip,niq->npq", Jall, Jall)                      # per candidate pose
    rows = 3 * k * len(cands)

    def gram(ch):
        return sum(Gp[offsets[j] + i] for j in ch for i in ch[j])
    G = gram(chosen)
    best = float(_o1_of_gram(G, rows))
    for _ in range(3):
        improved = False
        for j in cands:
            idx = offsets[j] + np.arange(len(cands[j]))
            for slot in range(k):
                cur = chosen[j][slot]
                o = _o1_of_gram(G - Gp[offsets[j] + cur] + Gp[idx], rows)
                others = set(chosen[j]) - {cur}
                pick = None
                for cand in range(len(cands[j])):
                    if cand == cur or cand in others:
                        continue
                    if o[cand] > best * (1 + 1e-9):
                        best, pick = float(o[cand]), cand
                if pick is not None:
                    chosen = {jj: list(v) for jj, v in chosen.items()}
                    chosen[j][slot] = pick
                    G = gram(chosen)
                    improved = True
        if not improved:
            break
    return chosen
