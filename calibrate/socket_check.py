"""How well a model explains socket readings it need not have been fitted to: consistency and distortion.

With the model fixed, each socket's centre is located from the model's ball positions alone (a seat: their
mean; a ball bar's pivot: the sphere of the read lengths), without the known distances. Then

- consistency (spread): the distance of every ball position from its socket's centre [mm] (ball bar: the
  length error); a perfect model puts every configuration of one socket on one point;
- distortion: each known socket distance as the model sees it, minus the stated one [mm].

These are the MUKCa paper's two measures; on placements the fit never saw they are the test of a calibration
without an external instrument.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import ModelParams, ball_positions
from .sockets import SocketReadings

__all__ = ["SocketCheck", "check_sockets", "socket_centres"]


@dataclass(frozen=True)
class SocketCheck:
    """Consistency and distortion of one model on one set of socket readings.

    spread_mm : shape=(N,) distance of each ball position from its socket's centre [mm] (ball bar: |length
    error|); distance_error_mm : shape=(K,) model distance minus stated [mm], one per placement and known pair;
    placements : the placements checked
    """

    spread_mm: np.ndarray
    distance_error_mm: np.ndarray
    placements: tuple

    @property
    def spread_rms_mm(self) -> float:
        return float(np.sqrt(np.mean(self.spread_mm ** 2)))

    @property
    def spread_max_mm(self) -> float:
        return float(self.spread_mm.max())

    @property
    def distance_rms_mm(self) -> float:
        e = self.distance_error_mm
        return float(np.sqrt(np.mean(e ** 2))) if e.size else float("nan")

    @property
    def distance_max_mm(self) -> float:
        e = self.distance_error_mm
        return float(np.abs(e).max()) if e.size else float("nan")

    def to_dict(self) -> dict:
        return {"placements": list(self.placements), "readings": int(self.spread_mm.size),
                "spread_mean_mm": float(self.spread_mm.mean()), "spread_rms_mm": self.spread_rms_mm,
                "spread_max_mm": self.spread_max_mm, "distance_errors_mm": self.distance_error_mm.tolist(),
                "distance_rms_mm": _or_none(self.distance_rms_mm), "distance_max_mm": _or_none(self.distance_max_mm)}


def _or_none(v: float) -> float | None:
    """JSON has no NaN: no known distance in these readings is ``null``."""
    return v if np.isfinite(v) else None


def _pivot(P: np.ndarray, L: np.ndarray, iterations: int = 20) -> np.ndarray:
    """Centre [mm] of the sphere through ``P`` (m, 3) with radii ``L`` (m,): algebraic start, Gauss-Newton."""
    A = np.c_[-2 * P, np.ones(len(P))]
    c = np.linalg.lstsq(A, L ** 2 - np.sum(P ** 2, axis=1), rcond=None)[0][:3]
    for _ in range(iterations):
        d = P - c
        rho = np.linalg.norm(d, axis=1)
        step = np.linalg.lstsq(-d / rho[:, None], L - rho, rcond=None)[0]
        c = c + step
        if np.linalg.norm(step) < 1e-9:
            break
    return c


def socket_centres(pW: np.ndarray, readings: SocketReadings) -> np.ndarray:
    """Each socket's centre [mm], shape=(G, 3) in the order of ``readings.groups()``, from the ball positions
    ``pW`` (N, 3) of one model alone: a seat's the mean, a ball bar's pivot the sphere of the read lengths."""
    g = readings.group_index()
    C = np.empty((len(readings.groups()), 3))
    for k in range(len(C)):
        m = g == k
        C[k] = _pivot(pW[m], readings.length_mm[m]) if readings.ball_bar else pW[m].mean(0)
    return C


def check_sockets(robot, params: ModelParams, readings: SocketReadings) -> SocketCheck:
    """Consistency and distortion of ``params`` on ``readings`` (see the module docstring)."""
    p = ball_positions(robot, params, readings.q_rad)[0].pW
    C = socket_centres(p, readings)
    rho = np.linalg.norm(p - C[readings.group_index()], axis=1)
    spread = np.abs(rho - readings.length_mm) if readings.ball_bar else rho
    pairs, stated = readings.distance_pairs()
    errors = np.linalg.norm(C[pairs[:, 0]] - C[pairs[:, 1]], axis=1) - stated
    return SocketCheck(spread, errors, tuple(dict.fromkeys(readings.placement.tolist())))
