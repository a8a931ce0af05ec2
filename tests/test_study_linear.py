"""The study's linear predictor (calibrate.predict_linear): its linear-algebra pieces against known truth, and
the predictor against Monte Carlo on a small case."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.calibrate import resolve_robot
from rodlab.calibrate.compensations import deflection_basis, deflection_offsets
from rodlab.calibrate.kinematics import ModelParams
from rodlab.calibrate.predict import Priors
from rodlab.calibrate.predict_linear import (compliance_draws, exact_mean_square, linear_campaign, predict_linear,
                                             random_parts, robot_prior, validation_draws)
from rodlab.calibrate.simulate import standard_base
from rodlab.core.enums import Method

from conftest import linear_and_monte_carlo


def test_deflection_basis_is_the_offsets_linear_map(rod4_plan):
    """Eq. 19 is linear in the compliance: the basis times (C_F, C_g) is deflection_offsets for any matrices."""
    robot, fixture, plan, rod = rod4_plan
    rng = np.random.default_rng(4)
    q = np.concatenate(list(plan.values()))
    F = rng.normal(0, 2.0, (q.shape[0], 3))
    p = ModelParams.nominal(robot, rod.tool_mm, base=standard_base())
    B = deflection_basis(robot, p, q, F, rod)
    for _ in range(3):
        G = rng.normal(0, 0.3, (3, 3))
        C_F, C_g = G @ G.T, rng.normal(0, 0.1, (3, 3))                 # C_F symmetric (Maxwell-Betti)
        other = type(rod)(rod.rod, rod.method, C_F, C_g, rod.mass_kg, rod.com_T_mm, rod.tool_mm)
        want = deflection_offsets(robot, p, q, F, other)
        np.testing.assert_allclose(B @ np.concatenate([C_F.ravel(), C_g.ravel()]), want, atol=1e-12)


def test_validation_refit_projects_out_base_and_tool():
    """After the base / tool refit nothing of their 9 columns remains: P J_v is orthogonal to them, and the
    projection keeps 3M - 9 of the validation noise's 3M dimensions."""
    robot = resolve_robot("tx90")
    vd = validation_draws(robot, Priors(validation_points=20), draws=3)
    assert vd.PJ.shape[:2] == (3, 60) and vd.Q.shape == (3, 60, 9)
    assert np.abs(np.swapaxes(vd.Q, 1, 2) @ vd.PJ).max() < 1e-9 * np.abs(vd.PJ).max()
    np.testing.assert_allclose(np.swapaxes(vd.Q, 1, 2) @ vd.Q, np.broadcast_to(np.eye(9), (3, 9, 9)), atol=1e-12)
    np.testing.assert_allclose(vd.W, np.swapaxes(vd.PJ, 1, 2) @ vd.PJ)


def test_unregularised_fit_recovers_the_parameters_exactly(rod4_plan):
    """With data that leave no scatter no parameter is regularised and A J = I: a perturbation of the free
    parameters is identified exactly (the linearised identification is unbiased)."""
    robot, fixture, plan, rod = rod4_plan
    lc = linear_campaign(robot, plan, fixture, standard_base(), rod)
    A = lc.gains(np.zeros((2, lc.J.shape[0])), rough=True)
    assert A.shape == (2, lc.J.shape[1], lc.J.shape[0])
    np.testing.assert_allclose(A[0] @ lc.J, np.eye(lc.J.shape[1]), atol=1e-8)
    # the gains through the inverse normal matrix are the solve of the normal equations
    ref = np.linalg.solve(lc.J.T @ lc.J, lc.J.T)
    np.testing.assert_allclose(A[0], ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max())
    # scatter and weak take a bool mask or column indices alike, and keep no reference to the caller's mask
    mask = ~lc.is_c
    idx = np.nonzero(mask)[0]
    y = np.random.default_rng(3).normal(0, 0.01, (2, lc.J.shape[0]))
    s1 = lc.scatter(y, mask)
    mask[:] = True
    np.testing.assert_array_equal(lc.scatter(y, idx), s1)
    np.testing.assert_array_equal(lc.weak(s1, idx), lc.weak(s1, ~lc.is_c))
    # a large scatter regularises the weakly seen parameters: their response shrinks
    big = lc.gains(np.full((1, lc.J.shape[0]), 0.0) + np.random.default_rng(1).normal(0, 5.0, (1, lc.J.shape[0])),
                   rough=False)
    assert np.trace(big[0] @ lc.J) < lc.J.shape[1] - 0.5


def test_perfect_files_leave_no_deflection_error(rod4_plan):
    """Files equal to the true rod: every compensating method gives the true-rod result (deflection share 0,
    meas = fea exactly); no compensation keeps the deflection."""
    robot, fixture, plan, rod = rod4_plan
    pri = Priors(r_rod=(1.0, 1.0), shape_sigma=0.0, meas_sigma=0.0, validation_points=30)
    out = {a.method: a for a in predict_linear(robot, plan, fixture, standard_base(), rod, rod,
                                               ["none", "fea", "meas"], pri, draws=64).summaries}
    assert out[Method.FEA].budget.deflection < 1e-9
    assert out[Method.MEAS].mean_mm == pytest.approx(out[Method.FEA].mean_mm, rel=1e-12)
    assert out[Method.NONE].budget.deflection > 0.5 and out[Method.NONE].mean_mm > 2 * out[Method.FEA].mean_mm
    for a in out.values():
        parts = (a.budget.deflection, a.budget.identification, a.budget.noise)
        assert sum(parts) == pytest.approx(1.0) and min(parts) >= 0
        assert a.mean_p05_mm <= a.mean_mm <= a.mean_p95_mm <= a.max_mm


def test_exact_mean_square_is_the_draws_expectation(rod4_plan):
    """The closed-form mean square (covariances propagated) equals the average of the drawn campaigns' mean
    squares within the draws' standard error (4 SE), validation noise included."""
    robot, fixture, plan, rod = rod4_plan
    pri = Priors(r_rod=(1.01, 1.05), validation_points=30)
    D = 1000
    lc = linear_campaign(robot, plan, fixture, standard_base(), rod, pri)
    vd = validation_draws(robot, pri, D, seed=5)
    mean, sd = robot_prior(robot, pri)
    rnd = random_parts(lc, vd, (mean, sd), pri, 5)
    _, dC, _ = compliance_draws(rod, None, [Method.FEA], pri, D, 5)
    E = lc.kinematic_map(vd.PJ.shape[2])
    y = rnd.xi @ lc.J_kin.T + rnd.eps + dC[Method.FEA] @ lc.B.T
    G = lc.inverse_normals(y, rough=True)
    A = lc.gains(y, rough=True)
    np.testing.assert_allclose(A, G @ lc.J.T, rtol=1e-12, atol=1e-14 * np.abs(A).max())
    e = np.einsum("dij,dj->di", vd.PJ, np.einsum("dpi,di->dp", A, y) @ E.T - rnd.xi) + rnd.Pn
    per = np.sum(e ** 2, axis=1) / vd.points
    exact = exact_mean_square(lc, vd, G, dC[Method.FEA], (mean, sd)) + \
        pri.instrument_noise_mm ** 2 * (3 * vd.points - 9) / vd.points
    assert abs(per.mean() - exact) < 4 * per.std() / np.sqrt(D)


def test_linear_predictor_agrees_with_monte_carlo(rod4_plan):
    """A steel rod, none and fea: the linear predictor's mean error lies within 3 Monte-Carlo standard errors
    (the spread of 12 replicates' mean errors / sqrt(12)) plus 3 % (linearisation: the campaign's true joint
    angles and second-order terms it leaves out) of the Monte-Carlo mean."""
    pri = Priors(r_rod=(1.01, 1.05), validation_points=50)
    R = 12
    lin, mc = linear_and_monte_carlo(rod4_plan, pri, R)
    for m in (Method.NONE, Method.FEA):
        se = np.std(mc[m].means_mm, ddof=1) / np.sqrt(R)
        assert abs(lin[m].mean_mm - mc[m].mean_mm) <= 3 * se + 0.03 * mc[m].mean_mm, (m, lin[m], mc[m], se)
    assert lin[Method.NONE].mean_mm > 1.5 * lin[Method.FEA].mean_mm


def test_kinematic_rows_and_precomputed_products_are_the_matrix_forms(rod4_plan):
    """``kinematic_rows`` is ``E G`` and the cached products are ``J^T J_kin`` and ``J^T Sigma J``: the exact mean
    square's P x P route equals the 3N x 3N one it replaced."""
    robot, fixture, plan, rod = rod4_plan
    lc = linear_campaign(robot, plan, fixture, standard_base(), rod)
    G = lc.inverse_normals(np.random.default_rng(2).normal(0, 0.01, (3, lc.J.shape[0])), rough=True)
    K = lc.J_kin.shape[1]
    E = lc.kinematic_map(K)
    np.testing.assert_array_equal(lc.kinematic_rows(G, K), E @ G)
    EA = E @ G @ lc.J.T
    scale = np.abs(EA @ lc.Sigma @ np.swapaxes(EA, 1, 2)).max()
    np.testing.assert_allclose(lc.kinematic_rows(G, K) @ lc.JtSigmaJ @ np.swapaxes(lc.kinematic_rows(G, K), 1, 2),
                               EA @ lc.Sigma @ np.swapaxes(EA, 1, 2), rtol=1e-9, atol=1e-12 * scale)
    np.testing.assert_allclose(EA @ lc.J_kin, lc.kinematic_rows(G, K) @ lc.JtJ_kin, rtol=1e-9, atol=1e-12)
