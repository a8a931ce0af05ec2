"""The rod's non-repeatable deflection (calibrate.rod_slip, Priors.rod_slip, study --rod-slip): its size, its
scaling with the compliance, and that both predictors carry it with every method."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.calibrate.compensations.rod_deflection import flange_loads
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.kinematics import ModelParams
from rodlab.calibrate.predict import Priors
from rodlab.calibrate.predict_linear import predict_linear
from rodlab.calibrate.rod_slip import slip_directions, slip_offsets
from rodlab.calibrate.simulate import standard_base
from rodlab.core.enums import Method

from conftest import linear_and_monte_carlo


def test_slip_is_the_deflection_under_a_random_load_of_its_weight(rod4_plan):
    """In {T} the offset is slip * C_g u (a rotation to {W} keeps its length); it doubles with the compliance
    and with slip, vanishes at 0, and its directions are N(0, I/3) (|u| ~ 1)."""
    robot, fixture, plan, rod = rod4_plan
    q = np.concatenate(list(plan.values()))
    p = ModelParams.nominal(robot, rod.tool_mm, base=standard_base())
    F = np.zeros((q.shape[0], 3))
    u = slip_directions(np.random.default_rng(1), q.shape[0])
    off = slip_offsets(robot, p, q, F, rod, 2.0, u)
    R_TW, _, _ = flange_loads(robot, p, q, F, rod)
    np.testing.assert_allclose(np.einsum("nji,nj->ni", R_TW, off), 2.0 * u @ rod.C_g.T, atol=1e-12)
    np.testing.assert_allclose(slip_offsets(robot, p, q, F, rod.scaled(2.0, Method.FEA), 1.0, u), off, atol=1e-12)
    assert not slip_offsets(robot, p, q, F, rod, 0.0, u).any()
    big = slip_directions(np.random.default_rng(2), 20000)
    np.testing.assert_allclose(np.cov(big.T), np.eye(3) / 3, atol=0.01)


def test_negative_slip_is_refused():
    with pytest.raises(CalibrationError, match="rod_slip"):
        Priors(rod_slip=-1.0)


def test_slip_stays_with_every_method_and_grows_with_the_compliance(rod4_plan):
    """Linear predictor, files equal to the true rod: without slip FEA ends where the robot's own noise puts it;
    with slip every method is worse by about the same, and a rod three times as compliant loses more."""
    robot, fixture, plan, rod = rod4_plan
    exact = dict(r_rod=(1.0, 1.0), shape_sigma=0.0, meas_sigma=0.0, validation_points=30)

    def mean(r, slip):
        out = predict_linear(robot, plan, fixture, standard_base(), r, None, ["none", "fea", "meas"],
                             Priors(rod_slip=slip, **exact), draws=128).summaries
        return {a.method: a.mean_mm for a in out}
    base, slipped = mean(rod, 0.0), mean(rod, 2.0)
    soft = rod.scaled(3.0, Method.FEA)
    soft0, soft2 = mean(soft, 0.0), mean(soft, 2.0)
    for m in (Method.FEA, Method.MEAS):
        assert slipped[m] > 1.5 * base[m]
        assert soft2[m] - soft0[m] > 2 * (slipped[m] - base[m])
    assert slipped[Method.FEA] == pytest.approx(slipped[Method.MEAS], rel=1e-6)   # the same files: same data
    assert slipped[Method.NONE] > slipped[Method.FEA]


def test_linear_predictor_agrees_with_monte_carlo_with_slip_and_floor(rod4_plan):
    """Steel rod 4#, the robot floor of the paper and the default slip in both paths: the linear predictor's
    mean within 3 Monte-Carlo standard errors plus 5 % of the Monte-Carlo mean (none and fea)."""
    pri = Priors(r_rod=(1.01, 1.05), validation_points=50, robot_floor_mm=0.263, rod_slip=2.4)
    R = 12
    lin, mc = linear_and_monte_carlo(rod4_plan, pri, R)
    for m in (Method.NONE, Method.FEA):
        se = np.std(mc[m].means_mm, ddof=1) / np.sqrt(R)
        assert abs(lin[m].mean_mm - mc[m].mean_mm) <= 3 * se + 0.05 * mc[m].mean_mm, (m, lin[m], mc[m], se)


def test_budget_gives_the_slip_its_own_share():
    """The four mean squares split as the module says; without the no-slip fit the slip stays in identification;
    a budget written before the split reads with slip 0."""
    from rodlab.calibrate.budget import BudgetShares, budget_shares
    b = budget_shares(ms=10.0, ms_true=8.0, ms_clean=1.0, ms_true_no_slip=3.0)
    assert (b.deflection, b.slip, b.identification, b.noise) == pytest.approx((0.2, 0.5, 0.2, 0.1))
    old = budget_shares(10.0, 8.0, 1.0)
    assert (old.deflection, old.slip, old.identification, old.noise) == pytest.approx((0.2, 0.0, 0.7, 0.1))
    assert BudgetShares.from_dict({"deflection": 0.2, "identification": 0.7, "noise": 0.1}).slip == 0.0
    assert BudgetShares.from_dict(b.to_dict()) == b


def test_a_campaign_without_its_slip_is_the_campaign_simulated_without_slip(rod4_plan):
    """Monte Carlo's slip share refits the campaign with the slip taken out of the readings: that must be, reading
    for reading, the campaign the same seed gives with no slip (the slip's directions come from their own
    generator, so nothing else moves)."""
    from rodlab.calibrate.predict import simulate_replicate
    robot, fixture, plan, rod = rod4_plan
    args = (robot, plan, fixture, standard_base(), rod, None, ["fea"])
    slipped = simulate_replicate(*args, Priors(rod_slip=2.4), seed=3).campaign
    elastic = simulate_replicate(*args, Priors(rod_slip=0.0), seed=3).campaign
    assert elastic.slip_D_mm is None and slipped.slip_D_mm is not None
    assert np.abs(slipped.x_D_mm - elastic.x_D_mm).max() > 0.01
    np.testing.assert_allclose(slipped.without_slip().x_D_mm, elastic.x_D_mm, atol=1e-9)


def test_both_predictors_put_the_soft_rods_error_on_its_slip(rod4_plan):
    """Rod 4# (steel, the paper's slip): most of every compensated method's error is the slip in both predictors
    (Monte Carlo with its extra fit, the linear one exactly), none of it without slip, and the shares agree."""
    from rodlab.calibrate.predict import predict_accuracy
    robot, fixture, plan, rod = rod4_plan
    pri = Priors(r_rod=(1.01, 1.05), validation_points=50, rod_slip=2.4)
    args = (robot, plan, fixture, standard_base(), rod, None, ["none", "fea"])
    lin = {a.method: a for a in predict_linear(*args, pri, draws=128).summaries}
    mc = {a.method: a for a in predict_accuracy(*args, pri, replicates=3, seed=0)}
    elastic = predict_linear(*args, Priors(r_rod=(1.01, 1.05), validation_points=50), draws=128).summaries
    for a in elastic:
        assert a.budget.slip == 0.0
    assert lin[Method.FEA].budget.slip > 0.8 and mc[Method.FEA].budget.slip > 0.8
    assert lin[Method.FEA].budget.slip == pytest.approx(mc[Method.FEA].budget.slip, abs=0.1)
    for a in (*lin.values(), *mc.values()):
        parts = (a.budget.deflection, a.budget.slip, a.budget.identification, a.budget.noise)
        assert sum(parts) == pytest.approx(1.0)
