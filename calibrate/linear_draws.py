"""The random parts of the linear predictor's draws (:mod:`calibrate.predict_linear`): the validation sets (base
and tool refitted), the truth's kinematic errors, the true rods and their compliance files, the campaign's and the
validation's noise, and the robot's own unmodelled error on the validation points; each from its own seeded
generator, the same for every design of a study.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method

from .errors import CalibrationError
from .jacobian import position_jacobian
from .kinematics import ball_positions
from .linear_campaign import LinearCampaign, kinematic_infos, linearisation_model
from .params import INTERNAL_SCALE, ParamInfo
from .predict import VALIDATION_ROD, Priors
from .unmodelled import validation_floor_offsets

__all__ = ["ValidationDraws", "validation_draws", "cached_validation_draws", "robot_prior", "compliance_draws",
           "Draws", "random_parts", "validation_sd", "validation_floor", "batched_mv"]


@dataclass(frozen=True)
class ValidationDraws:
    """The validation sets of the draws (as :func:`calibrate.predict` simulates them: random configurations
    within 60 % of the limits, the short validation rod), base and tool refitted.

    PJ : (D, 3M, K) the projected Jacobian ``P J_v`` w.r.t. the kinematic parameters [mm per internal unit];
    Q : (D, 3M, 9) orthonormal basis of the base / tool columns (``P = I - Q Q^T``); W : (D, K, K)
    ``(P J_v)^T P J_v``; q_rad : (D, M, n) the configurations [rad] (None: not kept; the robot floor is then
    isotropic scatter, :func:`validation_sd`)
    """

    PJ: np.ndarray
    Q: np.ndarray
    W: np.ndarray
    q_rad: np.ndarray | None = None

    @property
    def points(self) -> int:
        return self.PJ.shape[1] // 3


def validation_draws(robot, priors: Priors, draws: int, seed: int = 0) -> ValidationDraws:
    """``draws`` validation sets of ``priors.validation_points`` configurations each (seeded: the same for
    every design)."""
    rng = np.random.default_rng([seed, 1])
    M, D = int(priors.validation_points), int(draws)
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    vq = rng.uniform(lo * 0.6, hi * 0.6, (D * M, robot.n))
    model = linearisation_model(robot, VALIDATION_ROD.tool_mm, np.zeros(6), priors)
    fr, tau = ball_positions(robot, model, vq, VALIDATION_ROD)
    kin = kinematic_infos(robot.n)
    Jv = position_jacobian(fr, tau, kin, model.base).reshape(D, M * 3, len(kin))
    bt = [ParamInfo(f"base_{k}", "base_t", i, "mm") for i, k in enumerate("xyz")]
    bt += [ParamInfo(f"base_{k}", "base_r", i, "deg") for i, k in enumerate("abc")]
    bt += [ParamInfo(f"tool_{k}", "tool", i, "mm") for i, k in enumerate("xyz")]
    Jb = position_jacobian(fr, tau, bt, model.base).reshape(D, M * 3, len(bt))
    Q, _ = np.linalg.qr(Jb)
    PJ = Jv - Q @ (np.swapaxes(Q, 1, 2) @ Jv)
    return ValidationDraws(PJ, Q, np.swapaxes(PJ, 1, 2) @ PJ, vq.reshape(D, M, robot.n))


_CACHE: dict = {}


def cached_validation_draws(robot, priors: Priors, draws: int, seed: int = 0) -> ValidationDraws:
    """:func:`validation_draws`, kept for the process's next design (a study predicts many on one robot)."""
    key = (repr(robot), int(priors.validation_points), tuple(priors.joint_compliance), int(draws), int(seed))
    if key not in _CACHE:
        _CACHE.clear()                                  # one robot at a time: ~20 MB each
        _CACHE[key] = validation_draws(robot, priors, draws, seed)
    return _CACHE[key]


def robot_prior(robot, priors: Priors) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of the truth's kinematic errors [internal units] (K,) each, as
    :func:`calibrate.simulate.random_truth` draws them (the joint compliances uniform, from zero)."""
    par = set(robot.parallel_rows())
    s = float(priors.error_scale)
    lo, hi = (float(v) for v in priors.joint_compliance)
    mean, sd = [], []
    for info in kinematic_infos(robot.n):
        i, k = info.index, info.kind
        sig = {"dtheta": 0.06 * s, "a": 0.5 * s, "alpha": 0.05 * s, "d": 0.0 if i in par else 0.5 * s,
               "beta": 0.05 * s if i in par else 0.0, "c": 0.0 if i == 0 else (hi - lo) / np.sqrt(12)}[k]
        mu = 0.0 if k != "c" or i == 0 else (lo + hi) / 2
        mean.append(mu * INTERNAL_SCALE[info.unit])
        sd.append(sig * INTERNAL_SCALE[info.unit])
    return np.array(mean), np.array(sd)


def compliance_draws(reference: RodCompliance, calc: RodCompliance | None, methods, priors: Priors,
                     draws: int, seed: int = 0) -> tuple[np.ndarray, dict, np.ndarray]:
    """(r (D,), {method: (D, 18) vec(C_true - C_file)}, true (D, 18) vec(C_true)): the true rod
    ``r S C S^T`` with ``r`` stratified over its prior and ``S = I + shape_sigma N``, and the files as
    :func:`calibrate.predict` makes them (meas: the true ``C_F`` within ``meas_sigma``, ``r_meas C_g``)."""
    rng = np.random.default_rng([seed, 2])
    D = int(draws)
    lo, hi = priors.r_rod
    r = lo + (hi - lo) * (rng.permutation(D) + rng.uniform(0, 1, D)) / D
    S = np.eye(3) + priors.shape_sigma * rng.standard_normal((D, 3, 3))
    CF = r[:, None, None] * S @ reference.C_F @ np.swapaxes(S, 1, 2)
    Cg = r[:, None, None] * S @ reference.C_g @ np.swapaxes(S, 1, 2)
    true = np.concatenate([CF.reshape(D, 9), Cg.reshape(D, 9)], axis=1)
    Sm = np.eye(3) + priors.meas_sigma * rng.standard_normal((D, 3, 3))
    r_meas = r * (1.0 + priors.meas_sigma * rng.standard_normal(D))
    meas = np.concatenate([(Sm @ CF @ np.swapaxes(Sm, 1, 2)).reshape(D, 9),
                           (r_meas[:, None, None] * reference.C_g).reshape(D, 9)], axis=1)
    files = {}
    for m in methods:
        if m is Method.NONE:
            files[m] = np.zeros((D, 18))
        elif m is Method.CALC:
            if calc is None:
                raise CalibrationError("method calc needs the closed-form compliance file", key="methods")
            files[m] = np.tile(np.concatenate([calc.C_F.ravel(), calc.C_g.ravel()]), (D, 1))
        elif m is Method.FEA:
            files[m] = np.tile(np.concatenate([reference.C_F.ravel(), reference.C_g.ravel()]), (D, 1))
        else:
            files[m] = meas
    return r, {m: true - f for m, f in files.items()}, true


@dataclass(frozen=True)
class Draws:
    """The random parts of the draws (:func:`random_parts`): the truth's errors xi (D, K) [internal units], the
    campaign noise eps (D, 3N) [mm] and the validation noise Pn (D, 3M) [mm], projected off base and tool."""

    xi: np.ndarray
    eps: np.ndarray
    Pn: np.ndarray


def random_parts(lc: LinearCampaign, vd: ValidationDraws, prior: tuple, priors: Priors, seed: int) -> Draws:
    """The draws' random parts (:class:`Draws`) from the generator ``[seed, 3]``: the truth's errors from
    ``prior`` = (mean, sd) (:func:`robot_prior`; a joint compliance uniform, the rest Gaussian), the campaign
    noise with the covariance ``lc.Sigma`` and the validation scatter of ``priors``."""
    mean, sd = prior
    rng = np.random.default_rng([seed, 3])
    D = vd.PJ.shape[0]
    is_c = (mean > 0)
    xi = mean + sd * np.where(is_c, np.sqrt(12.0) * (rng.uniform(size=(D, mean.size)) - 0.5),
                              rng.standard_normal((D, mean.size)))
    L = np.linalg.cholesky(lc.Sigma + 1e-18 * np.eye(lc.Sigma.shape[0]))
    eps = rng.standard_normal((D, L.shape[0])) @ L.T
    n = validation_sd(priors, vd) * rng.standard_normal(vd.PJ.shape[:2])
    Pn = n - batched_mv(vd.Q, batched_mv(np.swapaxes(vd.Q, 1, 2), n))
    return Draws(xi, eps, Pn)


def validation_sd(priors: Priors, vd: ValidationDraws) -> float:
    """Per-coordinate scatter of a validation point [mm]: the instrument's noise; when the validation
    configurations are not kept (``vd.q_rad`` None) also, added in quadrature, the robot's own unmodelled error
    (``priors.robot_floor_mm``, as an isotropic error whose projected mean norm is that floor). With them the
    floor is realised instead, the same :class:`~calibrate.robot_floor.RobotFloor` per draw in the campaign and on
    validation (:func:`validation_floor`), as Monte Carlo does."""
    if vd.q_rad is not None:
        return float(priors.instrument_noise_mm)
    M, q = vd.points, vd.Q.shape[2]
    floor_sd = priors.robot_floor_mm / np.sqrt(8.0 / np.pi) / np.sqrt(max(3 * M - q, 1) / (3 * M))
    return float(np.hypot(priors.instrument_noise_mm, floor_sd))


def validation_floor(robot, vd: ValidationDraws, priors: Priors, seed: int) -> np.ndarray | None:
    """(D, 3M) [mm] the robot floor on the validation points, projected (the campaign's floor of each draw,
    :func:`calibrate.unmodelled.validation_floor_offsets`); None without a floor or without the configurations."""
    if not priors.robot_floor_mm > 0 or vd.q_rad is None:
        return None
    key = (repr(robot), float(priors.robot_floor_mm), tuple(priors.joint_compliance), int(seed),
           hash(vd.q_rad.tobytes()))
    if key not in _VFLOOR:                            # the same for every design: kept for the next one
        model = linearisation_model(robot, VALIDATION_ROD.tool_mm, np.zeros(6), priors)
        _VFLOOR.clear()
        _VFLOOR[key] = validation_floor_offsets(robot, model, vd.q_rad, VALIDATION_ROD, vd.Q, priors.robot_floor_mm,
                                                seed)
    return _VFLOOR[key]


_VFLOOR: dict = {}


def batched_mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix times vector: (D, i, j) @ (D, j) -> (D, i)."""
    return (A @ x[:, :, None])[:, :, 0]

