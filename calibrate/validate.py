"""Validation as in the paper (Section 5.2): the identified kinematic and joint-compliance parameters are
kept, only the base and the validation rod's tool are refitted on the validation points (measured by an
external instrument), and the position errors are summarised (mean, max, median, SD)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .points_file import PointSet
from .observations import register_base
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .params import ParamInfo, apply
from .points import points_observations

__all__ = ["ErrorStats", "validate", "error_stats", "clearly_worse", "WORSE_MIN_MM", "WORSE_MIN_SHARE"]


@dataclass(frozen=True)
class ErrorStats:
    """Position errors [mm] over ``points`` validation points."""

    mean_mm: float
    max_mm: float
    median_mm: float
    sd_mm: float
    points: int

    def to_dict(self) -> dict:
        return {"mean_mm": self.mean_mm, "max_mm": self.max_mm, "median_mm": self.median_mm, "sd_mm": self.sd_mm,
                "points": self.points}


def error_stats(err_mm: np.ndarray) -> ErrorStats:
    e = np.asarray(err_mm, float)
    return ErrorStats(float(e.mean()), float(e.max()), float(np.median(e)), float(e.std(ddof=1)) if e.size > 1 else 0.0,
                      int(e.size))


def validate(robot, model: ModelParams, pts: PointSet) -> tuple[ErrorStats, np.ndarray, ModelParams]:
    """Refit base and tool of ``model`` on ``pts``; return the statistics, per-point errors [mm] and the model."""
    from scipy.optimize import least_squares                            # heavy (scipy.optimize, ~0.3 s)

    start = model.with_(tool=np.asarray(pts.tool_mm, float))
    obs = points_observations(pts)
    start = start.with_(base=register_base(robot, start, obs))
    infos = [ParamInfo(f"base_{k}", "base_t", i, "mm") for i, k in enumerate("xyz")]
    infos += [ParamInfo(f"base_{k}", "base_r", i, "deg") for i, k in enumerate("abc")]
    infos += [ParamInfo(f"tool_{k}", "tool", i, "mm") for i, k in enumerate("xyz")]

    def frames(z):
        p = apply(start, infos, z)
        return p, ball_positions(robot, p, obs.q_rad, obs.rod)

    def fun(z):
        _, (fr, _) = frames(z)
        return (fr.pW - obs.x_W_mm).ravel()

    def jac(z):
        p, (fr, tau) = frames(z)
        return position_jacobian(fr, tau, infos, p.base).reshape(-1, len(infos))
    res = least_squares(fun, np.zeros(len(infos)), jac=jac, method="lm", xtol=1e-12, ftol=1e-12)
    p, (fr, _) = frames(res.x)
    err = np.linalg.norm(fr.pW - obs.x_W_mm, axis=1)
    return error_stats(err), err, p


#: validation errors are clearly worse only by at least this much [mm] ...
WORSE_MIN_MM = 0.002
#: ... and this share of the mean of the errors they are compared with
WORSE_MIN_SHARE = 0.05


def clearly_worse(with_mm: np.ndarray, without_mm: np.ndarray) -> bool:
    """Whether the validation errors ``with_mm`` [mm] are clearly worse than ``without_mm`` at the same points: the
    mean of the paired difference above two of its standard errors, :data:`WORSE_MIN_MM` and
    :data:`WORSE_MIN_SHARE` of the mean without."""
    d = np.asarray(with_mm, float) - np.asarray(without_mm, float)
    if d.size < 2:
        return False
    gain, se = float(d.mean()), float(d.std(ddof=1) / np.sqrt(d.size))
    return gain > 2.0 * se and gain > max(WORSE_MIN_MM, WORSE_MIN_SHARE * float(np.mean(without_mm)))
