"""Predicted calibration accuracy of a rod on a robot without Monte Carlo: the identification linearised.

The identification (:func:`calibrate.identify.identify`) is a least-squares fit of the free parameters to the
measured ball centres; around the robot's nominal model it is linear: a data perturbation ``y`` (3N) moves the
identified parameters by ``A y``, ``A = (J^T J + L^T L)^-1 J^T`` with ``J`` the planned campaign's Jacobian
(3N x P) and ``L`` the priors of the weakly identified parameters. What perturbs the data of one campaign:

- the robot's own errors ``xi`` (kinematic, joint compliance; the truth's prior): ``J_all xi``; a perfect fit
  takes them out exactly, except along the regularised parameters (the priors' pull);
- the device noise and the recorded fixture poses' uncertainty ``eps ~ N(0, Sigma)``
  (:func:`calibrate.observations.noise_covariance`);
- what the compensation leaves of the rod's deflection: the offsets are linear in the compliance (Eq. 19,
  :func:`calibrate.compensations.deflection_basis` ``B``), so the error is the *bias*
  ``B vec(C_true - C_file)``, ``C_true = r S C_FEA S^T`` with ``r`` from the material's r_rod prior;
- what neither the model nor any compensation describes, drawn per draw and added to the data as Monte Carlo
  adds it: the rod's non-repeatable deflection (:mod:`calibrate.rod_slip`, ``priors.rod_slip``) and the robot's
  own unmodelled error at the campaign's poses (``priors.robot_floor_mm``, one
  :class:`~calibrate.robot_floor.RobotFloor` per draw).

On the validation configurations (base and tool refitted: the projection ``P`` off their 9 columns) the error
of the identified model is ``e = P J_v (E A y - xi) + P n`` (``E`` picks the kinematic parameters, ``n`` the
instrument noise). Its mean square is exact in the Gaussian parts (traces of the propagated covariances) and
averaged over ``draws`` values of ``r`` (stratified over its prior), of the compliance's shape and of the
validation configurations; the mean / max / median of the per-point error norms, and the 5-95 % band of a
campaign's mean error, have no closed form and come from the same draws of the linear model, which cost
milliseconds. The error budget follows :mod:`calibrate.predict`: *deflection* = this method minus the true
rod's compliance, *slip* = the true rod's with the rod's slip minus without it, *identification* = the latter minus
the true robot's own model, *noise* = the latter (:mod:`calibrate.budget`).

Not modelled (Monte Carlo, :mod:`calibrate.predict`, has them): the campaign's joint angles are the planned
ones (the true robot stops within the alignment tolerance elsewhere), and second-order terms of the robot's
errors and of the compensation computed from the identified model.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method

from .budget import budget_shares
from .campaign import Fixture
from .linear_campaign import (KINEMATIC_KINDS, LinearCampaign, campaign_observations, linear_campaign,
                              linearisation_model, right_product)
from .linear_draws import (Draws, ValidationDraws, batched_mv, cached_validation_draws, compliance_draws,
                           random_parts, robot_prior, validation_draws, validation_floor, validation_sd)
from .predict import AccuracySummary, Priors
from .rod import Rod
from .unmodelled import campaign_offsets

__all__ = ["LinearPrediction", "predict_linear", "exact_mean_square",
           # the campaign's linear model and the draws, from their own modules
           "LinearCampaign", "linear_campaign", "linearisation_model", "KINEMATIC_KINDS", "ValidationDraws",
           "validation_draws", "cached_validation_draws", "robot_prior", "compliance_draws", "Draws", "random_parts"]


@dataclass(frozen=True)
class LinearPrediction:
    """The linear predictor's result: one :class:`~calibrate.predict.AccuracySummary` per method (``replicates``
    = the draws), the nominal model's mean validation error [mm] and the validation noise floor's mean square
    [mm^2]."""

    summaries: list
    nominal_mean_mm: float
    ms_noise_mm2: float
    draws: int


def exact_mean_square(lc: LinearCampaign, vd: ValidationDraws, G: np.ndarray, dC: np.ndarray, prior: tuple,
                      extra: np.ndarray | None = None, val_extra: np.ndarray | None = None) -> float:
    """Mean-square validation error [mm^2] (without the validation noise) over the draws' compliances,
    regularisations and validation sets, the Gaussian parts (campaign noise, the truth's spread) by their
    covariance: ``mean_d (|P J_v v_d|^2 + tr(W_d Cov_d)) / M`` (``W_d = (P J_v)^T P J_v``, ``vd.W``).

    G : (D, P, P) each draw's inverse normal matrix (:meth:`LinearCampaign.inverse_normals`; the gains are
    ``A = G J^T``, so ``E A Sigma A^T E^T = E G (J^T Sigma J) G E^T``: P x P products instead of 3N x 3N);
    dC : (D, 18) what the compensation leaves of each draw's compliance, ``vec(C_true - C_file)`` (the data's
    bias ``B dC``); prior : (mean, sd) (K,) of the truth's kinematic errors (:func:`robot_prior`); extra :
    (D, 3N) [mm] further bias of the data (the rod's slip, the robot floor at the campaign's poses; None: none);
    val_extra : (D, 3M) [mm] on validation (the robot floor there, projected; None: none)."""
    mean, sd = prior
    K = vd.PJ.shape[2]
    X = lc.kinematic_rows(G, K)                                       # (D, K, P) E G
    R = right_product(X, lc.JtJ_kin) - np.eye(K)                             # E A J_kin - I
    bias = dC @ lc.B.T if extra is None else dC @ lc.B.T + extra
    v = batched_mv(X, bias @ lc.J) + R @ mean                                # (D, K) mean kinematic error
    ev = batched_mv(vd.PJ, v) if val_extra is None else batched_mv(vd.PJ, v) + val_extra
    bias = np.sum(ev ** 2, axis=1)
    cov = (R * sd ** 2) @ np.swapaxes(R, 1, 2) + right_product(X, lc.JtSigmaJ) @ np.swapaxes(X, 1, 2)
    return float(np.mean(bias + np.sum(vd.W * cov, axis=(1, 2)))) / vd.points






def _stats(e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    norms = np.linalg.norm(e.reshape(e.shape[0], -1, 3), axis=2)
    return norms.mean(axis=1), norms.max(axis=1), np.median(norms, axis=1)


def predict_linear(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                   calc: RodCompliance | None = None, methods=(Method.NONE, Method.FEA, Method.MEAS),
                   priors: Priors = Priors(), draws: int = 256, seed: int = 0,
                   validation: ValidationDraws | None = None) -> LinearPrediction:
    """The predicted validation accuracy per method from the planned campaign (see the module docstring); the
    arguments as :func:`calibrate.predict.predict_accuracy`'s, ``draws`` of the linear model in place of
    its replicates; ``validation``: :func:`validation_draws` computed once for many designs."""
    methods = [Method.parse(m, "method") for m in methods]
    lc = linear_campaign(robot, plan_q, fixture, base, reference, priors)
    vd = validation if validation is not None else cached_validation_draws(robot, priors, draws, seed)
    D, K = vd.PJ.shape[0], vd.PJ.shape[2]
    mean, sd = robot_prior(robot, priors)
    rnd = random_parts(lc, vd, (mean, sd), priors, seed)
    _, dC, true = compliance_draws(reference, calc, methods, priors, D, seed)
    extra, floor_only = _unmodelled_data(robot, plan_q, fixture, base, reference, priors, true, seed, D, lc)
    E = lc.kinematic_map(K)
    M = vd.points
    ms_noise = validation_sd(priors, vd) ** 2 * (3 * M - vd.Q.shape[2]) / M
    vf = validation_floor(robot, vd, priors, seed)
    Pn = rnd.Pn if vf is None else rnd.Pn + vf                        # validation scatter: noise and floor
    ms_clean = ms_noise if vf is None else ms_noise + float(np.mean(np.sum(vf ** 2, axis=1))) / M
    y_robot = rnd.xi @ lc.J_kin.T + rnd.eps + extra
    G_true = lc.inverse_normals(y_robot, rough=True)
    ms_true = exact_mean_square(lc, vd, G_true, np.zeros((D, 18)), (mean, sd), extra, vf) + ms_noise
    ms_no_slip = float("nan")
    if priors.rod_slip:                                               # the slip's own share of the budget
        G_ns = lc.inverse_normals(rnd.xi @ lc.J_kin.T + rnd.eps + floor_only, rough=True)
        ms_no_slip = exact_mean_square(lc, vd, G_ns, np.zeros((D, 18)), (mean, sd), floor_only, vf) + ms_noise
    out = []
    for m in methods:
        y = y_robot + dC[m] @ lc.B.T
        G = lc.inverse_normals(y, rough=m is not Method.NONE)
        delta = batched_mv(G, y @ lc.J) @ E.T - rnd.xi
        means, maxs, medians = _stats(batched_mv(vd.PJ, delta) + Pn)
        ms = exact_mean_square(lc, vd, G, dC[m], (mean, sd), extra, vf) + ms_noise
        out.append(AccuracySummary(m, float(means.mean()), float(maxs.mean()), float(medians.mean()),
                                   float(np.percentile(means, 5)), float(np.percentile(means, 95)),
                                   float(np.sqrt(ms)), budget_shares(ms, ms_true, ms_clean, ms_no_slip), D, 0,
                                   tuple(float(v) for v in means)))
    nominal = _stats(Pn - batched_mv(vd.PJ, rnd.xi))[0]
    return LinearPrediction(out, float(nominal.mean()), float(ms_clean), D)


def _unmodelled_data(robot, plan_q, fixture, base, reference, priors: Priors, true: np.ndarray, seed: int, D: int,
                     lc: LinearCampaign) -> tuple[np.ndarray, np.ndarray]:
    """(D, 3N) [mm] twice: what neither model nor compensation describes in the campaign's data per draw — the
    rod's slip and the robot floor at its poses — and the robot floor alone (zeros where the priors have none)."""
    zero = np.zeros((D, lc.J.shape[0]))
    if not priors.rod_slip and priors.robot_floor_mm <= 0:
        return zero, zero
    model = linearisation_model(robot, reference.tool_mm, base, priors)
    obs = campaign_observations(robot, model, plan_q, fixture, Rod.of(reference))
    floor = (campaign_offsets(robot, model, obs, replace(priors, rod_slip=0.0), true, seed)
             if priors.robot_floor_mm > 0 else zero)
    slip = (campaign_offsets(robot, model, obs, replace(priors, robot_floor_mm=0.0), true, seed)
            if priors.rod_slip else zero)                 # each from its own generator: their sum is the draws' both
    return slip + floor, floor
