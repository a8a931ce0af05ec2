"""Synthetic ball-in-socket and ball-bar readings of a known robot: the tests' and the blind checks' data.

An artefact with ``sockets`` sockets on a line (``spacing_mm`` apart) is put at ``placements`` reachable places
of the workspace, in random directions; at each socket the true robot reaches the socket centre plus the seat's
play (normal, ``seat_sigma_mm`` per coordinate) from random seed configurations, so the arm's configuration
differs from reading to reading. A ball bar: one pivot per placement and readings on the sphere of radius
``bar_mm`` around it (upper half), each length read with ``length_sigma_mm`` of noise.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .ik import random_configurations, solve_ik_positions
from .kinematics import ModelParams, ball_positions
from .sockets import SocketDistance, SocketReadings

__all__ = ["SocketSpec", "simulate_sockets"]


@dataclass(frozen=True)
class SocketSpec:
    """placements : artefact places; sockets : sockets per artefact (on a line); spacing_mm : their distance
    [mm]; readings : configurations recorded per socket; seat_sigma_mm : play of the ball in a seat (1 sigma
    per coordinate) [mm]; bar_mm : ball-bar length [mm] (0: seat readings); length_sigma_mm : ball-bar noise
    [mm]; reach : fraction of the joint ranges the placements are drawn from"""

    placements: int = 4
    sockets: int = 2
    spacing_mm: float = 50.0
    readings: int = 15
    seat_sigma_mm: float = 0.02
    bar_mm: float = 0.0
    length_sigma_mm: float = 0.002
    reach: float = 0.5


def _places(robot, truth: ModelParams, spec: SocketSpec, rng) -> list[np.ndarray]:
    """Socket centres of each placement [mm], each shape=(sockets, 3): a reachable point, then the others along
    a random horizontal direction."""
    q = random_configurations(robot, rng, spec.placements, spec.reach)
    p0 = ball_positions(robot, truth, q)[0].pW
    out = []
    for p in p0:
        phi = rng.uniform(0, 2 * np.pi)
        u = np.array([np.cos(phi), np.sin(phi), 0.0])
        out.append(p + spec.spacing_mm * np.arange(spec.sockets)[:, None] * u)
    return out


def _reach(robot, truth: ModelParams, targets: np.ndarray, rng, tries: int = 6) -> tuple[np.ndarray, np.ndarray]:
    """Configurations that put the true ball at ``targets`` (M, 3) from random seeds; the ones reached."""
    M = len(targets)
    seeds = random_configurations(robot, rng, M * tries, 0.9)
    res = solve_ik_positions(robot, truth, np.repeat(targets, tries, axis=0), seeds)
    ok = res.ok.reshape(M, tries)
    pick = np.argmax(ok, axis=1)
    return res.q_rad.reshape(M, tries, -1)[np.arange(M), pick], ok.any(axis=1)


def simulate_sockets(robot, truth: ModelParams, spec: SocketSpec = SocketSpec(), seed: int = 0) -> SocketReadings:
    """Readings of ``truth`` (the real robot) per ``spec``; the file states ``spec``'s uncertainties."""
    rng = np.random.default_rng(seed)
    q, pl, so, L = [], [], [], []
    for j, centres in enumerate(_places(robot, truth, spec, rng), start=1):
        for s, c in enumerate(centres, start=1):
            if spec.bar_mm > 0:
                u = rng.normal(size=(spec.readings, 3))
                u[:, 2] = np.abs(u[:, 2])
                targets = c + spec.bar_mm * u / np.linalg.norm(u, axis=1)[:, None]
            else:
                targets = c + rng.normal(0.0, spec.seat_sigma_mm, (spec.readings, 3))
            qs, ok = _reach(robot, truth, targets, rng)
            q.append(qs[ok])
            pl += [j] * int(ok.sum())
            so += [s] * int(ok.sum())
            if spec.bar_mm > 0:
                true_L = np.linalg.norm(ball_positions(robot, truth, qs[ok])[0].pW - c, axis=1)
                L.append(true_L + rng.normal(0.0, spec.length_sigma_mm, true_L.size))
    distances = tuple(SocketDistance(a, b, spec.spacing_mm * (b - a)) for a in range(1, spec.sockets + 1)
                      for b in range(a + 1, spec.sockets + 1))
    return SocketReadings(np.concatenate(q), np.array(pl), np.array(so),
                          np.concatenate(L) if spec.bar_mm > 0 else None, distances, np.asarray(truth.tool, float),
                          spec.seat_sigma_mm, 0.001, spec.length_sigma_mm)
