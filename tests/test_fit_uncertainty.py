"""Standard errors that do not hide what the data cannot see, and observation subsets that keep every field."""
from __future__ import annotations

import numpy as np

from rodlab.calibrate.covariance import correlation, parameter_covariance
from rodlab.calibrate.identify import Observations
from rodlab.calibrate.rod import Rod


def test_well_posed_covariance_is_the_inverse_normal_matrix():
    rng = np.random.default_rng(0)
    J = rng.normal(size=(40, 4)) * [1.0, 1e3, 1e-4, 10.0]          # columns in very different units
    assert np.allclose(parameter_covariance(J), np.linalg.inv(J.T @ J), rtol=1e-9)


def test_a_direction_the_data_do_not_see_has_infinite_variance_not_zero():
    """pinv(J^T J) gives a parameter with a vanishing column a variance of 0 (the best known); here: inf."""
    rng = np.random.default_rng(1)
    J = rng.normal(size=(40, 3))
    J[:, 2] = 1e-13 * J[:, 0]                                       # seen only at round-off, along another
    assert np.linalg.pinv(J.T @ J)[2, 2] < 1e-3                      # the trap
    cov = parameter_covariance(J)
    assert np.isinf(cov[2, 2]) and np.isinf(cov[0, 0]) and np.isfinite(cov[1, 1])
    assert np.isnan(correlation(cov)[2]).all()


def test_subset_keeps_every_per_point_field():
    """Outliers removed by the diagnoser used to drop the temperatures (and sigmas) of the points kept."""
    n = 6
    obs = Observations(np.zeros((n, 6)), np.arange(3 * n, dtype=float).reshape(n, 3), np.ones((n, 3)),
                       Rod.rigid(np.zeros(3), 1.5), np.arange(n) % 2, [f"p{i}" for i in range(n)], None,
                       np.ones((n, 3)), np.full((n, 3), 0.01), np.linspace(20, 25, n))
    keep = np.array([True, False, True, True, False, True])
    sub = obs.subset(keep)
    assert sub.x_W_mm.shape == (4, 3) and sub.labels == ["p0", "p2", "p3", "p5"]
    assert np.array_equal(sub.temp_C, obs.temp_C[keep]) and sub.sigma_mm.shape == (4, 3)
    assert np.array_equal(sub.group, [0, 0, 1, 1]) and sub.rod.mass_kg == 1.5


def test_fewer_readings_than_parameters_leave_some_unseen():
    """Two readings cannot fix four parameters: the null space (absent from a thin SVD) is unseen too."""
    J = np.random.default_rng(2).normal(size=(2, 4))
    assert np.isinf(np.diag(parameter_covariance(J))).sum() >= 2


def test_an_infinite_sigma_survives_the_result_file(tmp_path):
    """JSON writes an infinite standard error as null; reading it back must not give 0 (the best known)."""
    import json
    from rodlab.calibrate.result import read_calibration
    doc = {"format": "rodlab.calibration/1", "robot": "tx90", "compensation": "calc", "trusted": False,
           "parameters": {"d_2": {"value": 0.1, "sigma": None, "unit": "mm", "status": "identified"},
                          "a_2": {"value": 0.2, "sigma": 0.01, "unit": "mm", "status": "identified"},
                          "d_1": {"value": 0.0, "unit": "mm", "status": "fixed"}}}
    path = tmp_path / "cal.json"
    path.write_text(json.dumps(doc))
    cal = read_calibration(path)
    assert np.isinf(cal.parameters["d_2"].sigma) and cal.parameters["a_2"].sigma == 0.01
    assert cal.parameters["d_1"].sigma == 0.0
