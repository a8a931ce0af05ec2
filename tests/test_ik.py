"""Batched position IK (calibrate.ik): known-truth recovery over many configurations at once."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.calibrate import Rod, resolve_robot
from rodlab.calibrate.ik import PLAN_PULL_ITERATIONS, solve_ik_position, solve_ik_positions
from rodlab.calibrate.kinematics import ball_positions
from rodlab.calibrate.simulate import random_truth
from rodlab import calc_rod_compliance, resolve_design


@pytest.fixture(scope="module")
def setup():
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(resolve_design("rod1"))
    rng = np.random.default_rng(5)
    truth = random_truth(robot, rod.tool_mm, rng)          # kinematic errors and compliant joints
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    return robot, rod, truth, rng, lo, hi


def test_batch_reaches_targets_of_known_configurations(setup):
    """Targets made by forward kinematics of known configurations (rod weight and a contact force deflect the
    joints): the solver brings the ball back to each target within the tolerance, inside the limits."""
    robot, rod, truth, rng, lo, hi = setup
    F = np.array([1.1, 1.25, 1.05])
    q_true = rng.uniform(0.6 * lo, 0.6 * hi, (120, robot.n))
    targets = ball_positions(robot, truth, q_true, Rod.of(rod), force_W_N=np.tile(F, (120, 1)))[0].pW
    seeds = rng.uniform(0.7 * lo, 0.7 * hi, (120, robot.n))
    res = solve_ik_positions(robot, truth, targets, seeds, Rod.of(rod), F)
    assert res.ok.mean() > 0.85                                  # random far seeds: a few end in local minima
    assert np.all(res.error_mm[res.ok] < 1e-4)
    pW = ball_positions(robot, truth, res.q_rad[res.ok], Rod.of(rod),
                        force_W_N=np.tile(F, (int(res.ok.sum()), 1)))[0].pW
    np.testing.assert_allclose(pW, targets[res.ok], atol=1e-4)  # independently recomputed
    assert np.all(res.q_rad >= lo - 1e-12) and np.all(res.q_rad <= hi + 1e-12)


def test_seed_pull_gives_different_orientations_for_one_point(setup):
    """One target from many seeds: different joint solutions (the rod orientations a planner chooses from)."""
    robot, rod, truth, rng, lo, hi = setup
    target = ball_positions(robot, truth, np.zeros((1, robot.n)) + 0.3, Rod.of(rod))[0].pW[0]
    seeds = rng.uniform(0.7 * lo, 0.7 * hi, (40, robot.n))
    res = solve_ik_positions(robot, truth, target, seeds, Rod.of(rod))
    q = res.q_rad[res.ok]
    assert len(q) >= 20
    spread = np.rad2deg(q.max(axis=0) - q.min(axis=0))
    assert spread[3:].min() > 30.0                              # the wrist takes many orientations


def test_a_planners_short_pull_reaches_as_many_targets_as_the_full_one(setup):
    """The planner cuts stage 1 (the pull towards each seed) at PLAN_PULL_ITERATIONS: it reaches as many of
    600 targets within the tolerance as the full 60 iterations (within 2 %), in fewer iterations, its
    solutions still spread over the wrist's orientations."""
    robot, rod, truth, rng, lo, hi = setup
    q_true = rng.uniform(0.5 * lo, 0.5 * hi, (5, robot.n))
    targets = np.repeat(ball_positions(robot, truth, q_true, Rod.of(rod))[0].pW, 120, axis=0)
    seeds = rng.uniform(0.7 * lo, 0.7 * hi, (600, robot.n))
    full = solve_ik_positions(robot, truth, targets, seeds, Rod.of(rod))
    short = solve_ik_positions(robot, truth, targets, seeds, Rod.of(rod), pull_iterations=PLAN_PULL_ITERATIONS)
    assert short.ok.sum() >= 0.98 * full.ok.sum() > 0.8 * 600
    assert short.iterations < full.iterations
    assert np.all(short.error_mm[short.ok] < 1e-4)
    q = short.q_rad[short.ok][:100]
    assert np.rad2deg(q.max(axis=0) - q.min(axis=0))[3:].min() > 30.0


def test_single_configuration_wrapper_equals_batch(setup):
    robot, rod, truth, rng, lo, hi = setup
    q_true = rng.uniform(0.5 * lo, 0.5 * hi, (3, robot.n))
    targets = ball_positions(robot, truth, q_true)[0].pW
    batch = solve_ik_positions(robot, truth, targets, q_true + 0.05)
    for i in range(3):
        one = solve_ik_position(robot, truth, targets[i], q_true[i] + 0.05)
        assert batch.ok[i] and one is not None
        np.testing.assert_allclose(one, batch.q_rad[i], atol=1e-9)


def test_unreachable_target_is_reported_not_returned(setup):
    robot, rod, truth, rng, lo, hi = setup
    far = np.array([5000.0, 0.0, 0.0])                           # 5 m: beyond any TX90 configuration
    res = solve_ik_positions(robot, truth, far, rng.uniform(lo, hi, (4, robot.n)))
    assert not res.ok.any() and np.all(res.error_mm > 1000.0)
    assert solve_ik_position(robot, truth, far, np.zeros(robot.n)) is None


def test_static_torques_equal_the_sum_over_loads_beyond_each_joint(setup):
    """The suffix-sum form equals the definition: tau_i = sum over every load k beyond joint i of
    z_{i-1} . ((c_k - o_{i-1}) x F_k), written out load by load with np.cross."""
    from rodlab.calibrate.kinematics import forward, static_torques
    robot, rod, truth, rng, lo, hi = setup
    q = rng.uniform(lo, hi, (25, robot.n))
    fr = forward(truth, q)
    F_W = rng.normal(size=(25, 3))
    com = np.array([3.0, -2.0, -80.0])
    tau = static_torques(robot, fr, Rod.rigid(np.zeros(3), 0.7, com), F_W)
    g0 = np.asarray(robot.gravity_base, float)
    n = robot.n
    loads = [(k, fr.T[:, k + 1, :3, :3] @ robot.com_mm[k] + fr.T[:, k + 1, :3, 3], robot.mass_kg[k] * g0)
             for k in range(n)]
    loads += [(n - 1, fr.p0 + fr.T[:, n, :3, :3] @ com, 0.7 * g0), (n - 1, fr.p0, F_W @ fr.R_W0)]
    ref = np.zeros_like(tau)
    for i in range(n):
        for k, c, F in loads:
            if k >= i:
                arm = c - fr.o_prev[:, i]
                ref[:, i] += np.einsum("mj,mj->m", fr.z_prev[:, i], np.cross(arm, np.broadcast_to(F, arm.shape)))
    np.testing.assert_allclose(tau, ref * 1e-3, atol=1e-12 * np.abs(ref).max())


def test_the_rods_weight_as_two_numbers_still_works_with_a_warning(setup):
    """ball_positions' old signature (the rod's mass and centre of mass as two numbers, positional or by keyword)
    gives the same frames and torques as the rod, with a DeprecationWarning."""
    robot, rod, truth, rng, lo, hi = setup
    q = rng.uniform(0.5 * lo, 0.5 * hi, (5, robot.n))
    F = np.tile([1.1, 1.25, 1.05], (5, 1))
    fr, tau = ball_positions(robot, truth, q, Rod.of(rod), force_W_N=F)
    olds = []
    for args, kw in ((( rod.mass_kg, rod.com_T_mm, F), {}), ((rod.mass_kg, rod.com_T_mm, F, 2), {}),
                     ((rod.mass_kg, rod.com_T_mm), {"force_W_N": F}), ((rod.mass_kg, rod.com_T_mm, F), {"iterations": 2}),
                     ((), {"rod_mass_kg": rod.mass_kg, "rod_com_T_mm": rod.com_T_mm, "force_W_N": F})):
        with pytest.warns(DeprecationWarning, match="pass the rod as a Rod"):
            olds.append(ball_positions(robot, truth, q, *args, **kw))
    for fr_o, tau_o in olds:
        np.testing.assert_array_equal(fr_o.pW, fr.pW)
        np.testing.assert_array_equal(tau_o, tau)
    one = ball_positions(robot, truth, q, Rod.of(rod), force_W_N=F, iterations=1)
    with pytest.warns(DeprecationWarning):
        one_old = ball_positions(robot, truth, q, rod.mass_kg, rod.com_T_mm, F, iterations=1)
    np.testing.assert_array_equal(one_old[0].pW, one[0].pW)                   # iterations are kept, not reset
    with pytest.raises(TypeError, match="by keyword"):
        ball_positions(robot, truth, q, Rod.of(rod), F)
    unloaded = ball_positions(robot, truth, q, None, force_W_N=F)[1]
    assert np.abs(tau - unloaded).max() > 1.0                   # the rod's weight is not lost on the way


def test_a_pull_of_no_iterations_is_refused_with_the_fix(setup):
    from rodlab.calibrate import CalibrationError
    robot, rod, truth, rng, lo, hi = setup
    with pytest.raises(CalibrationError, match="pull=False"):
        solve_ik_positions(robot, truth, np.zeros(3), np.zeros((1, robot.n)), pull_iterations=0)
