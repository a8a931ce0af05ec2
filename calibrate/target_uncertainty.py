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
#: TCP motion [mm per internal unit: mm or rad] below which a parameter the data do not see leaves a target alone
UNSEEN_TOL_MM = 1e-9


def tcp_sd_mm(robot, params: ModelParams, q_rad: np.ndarray, cal) -> np.ndarray | None:
    """1-sigma position uncertainty [mm], shape=(M,), of the TCP of ``params`` (the calibrated model with the
    production tool) at the joint commands ``q_rad`` (M, n), from the covariance of the calibration file ``cal``
    (:class:`~calibrate.result.CalibrationFile`); None when the file records no correlation; infinite at the targets
    whose TCP a parameter without a finite sigma (a direction the data do not see) moves."""
    if cal.correlation is None:
        return None
    infos = {i.name: i for i in catalogue(robot.n, (), tuple(sorted(cal.harmonic_reference)))}
    names = [n for n in cal.correlation_names if n in infos and not n.startswith(LEFT_OUT)]
    idx = [cal.correlation_names.index(n) for n in names]
    sigma = np.array([cal.parameters[n].sigma * INTERNAL_SCALE[infos[n].unit] for n in names])
    q = np.atleast_2d(q_rad)
    fr, tau = ball_positions(robot, params, q, None)
    J = position_jacobian(fr, tau, [infos[n] for n in names], params.base)
    seen = np.isfinite(sigma)
    cov = cal.correlation[np.ix_(idx, idx)][np.ix_(seen, seen)] * np.outer(sigma[seen], sigma[seen])
    sd = np.sqrt(np.clip(np.einsum("mip,pq,miq->m", J[:, :, seen], cov, J[:, :, seen]), 0.0, None))
    return np.where(_moved_by_unseen(J[:, :, ~seen]), np.inf, sd)


def _moved_by_unseen(J_unseen: np.ndarray) -> np.ndarray:
    """Per target, shape=(M,): whether a parameter the data do not see (no finite sigma) moves its TCP at all
    (more than ``UNSEEN_TOL_MM`` per internal unit): its uncertainty is then unbounded; one that leaves the
    target's TCP where it is (a twist about the axis through it) costs that target nothing."""
    if J_unseen.shape[-1] == 0:
        return np.zeros(J_unseen.shape[0], dtype=bool)
    return np.linalg.norm(J_unseen, axis=1).max(axis=1) > UNSEEN_TOL_MM
