"""How well a calibration pins each target: the TCP's position uncertainty from the identified parameters.

The identification's covariance of the free parameters (their standard deviations and correlation, recorded in
the result as ``fit.correlation``) propagated through the TCP's position Jacobian at each target's joint commands
gives a per-target 1-sigma uncertainty (RSS over x, y, z) of where the calibrated model puts the TCP. It grows
where a target lies away from the poses the campaign measured (an extrapolation) and is what the held-out mean
error cannot show per target; the error the model leaves out (the residual test's excess) adds to it. The tool
and fixture parameters are the rod's and the campaign's, not the production tool's: left out.
"""
from __future__ import annotations

import numpy as np

from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .params import INTERNAL_SCALE, catalogue

__all__ = ["tcp_sd_mm", "LEFT_OUT"]

#: parameters of the rod and the campaign, not of the robot at its targets
LEFT_OUT = ("tool_", "fixture_")


def tcp_sd_mm(robot, params: ModelParams, q_rad: np.ndarray, cal) -> np.ndarray | None:
    """1-sigma position uncertainty [mm], shape=(M,), of the TCP of ``params`` (the calibrated model with the
    production tool) at the joint commands ``q_rad`` (M, n), from the covariance of the calibration file ``cal``
    (:class:`~calibrate.result.CalibrationFile`); None when the file records no correlation; infinite where a
    parameter it uses has no finite sigma (a direction the data do not see)."""
    if cal.correlation is None:
        return None
    infos = {i.name: i for i in catalogue(robot.n, (), tuple(sorted(cal.harmonic_reference)))}
    names = [n for n in cal.correlation_names if n in infos and not n.startswith(LEFT_OUT)]
    idx = [cal.correlation_names.index(n) for n in names]
    sigma = np.array([cal.parameters[n].sigma * INTERNAL_SCALE[infos[n].unit] for n in names])
    cov = cal.correlation[np.ix_(idx, idx)] * np.outer(sigma, sigma)
    q = np.atleast_2d(q_rad)
    if not np.all(np.isfinite(cov)):                 # a parameter the data do not see: unbounded
        return np.full(len(q), np.inf)
    fr, tau = ball_positions(robot, params, q, None)
    J = position_jacobian(fr, tau, [infos[n] for n in names], params.base)
    return np.sqrt(np.clip(np.einsum("mip,pq,miq->m", J, cov, J), 0.0, None))
