"""A points file's temperature column (a trial: the UR10's raw data had one per point, and the points format had
refused it): read, and the points' diagnosis tests the arm's thermal growth with it."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.app.cli import main
from rodlab.calibrate import read_points, resolve_robot
from rodlab.calibrate.kinematics import ModelParams, forward


def _points(path, growth_ppm_per_K: float, seed: int = 5):
    """60 poses of the nominal TX90, every point moved from the base by growth x (T - mean T), 10 um noise."""
    robot = resolve_robot("tx90")
    rng = np.random.default_rng(seed)
    p = ModelParams.nominal(robot, np.array([0.0, 0.0, 150.0]))
    q = rng.uniform(-1.0, 1.0, (60, 6)) * np.radians([90, 60, 70, 110, 60, 110])
    fr = forward(p, q)
    T = 20.0 + 4.0 * rng.random(60)
    x = fr.p0 * (1 + growth_ppm_per_K * 1e-6 * (T - T.mean()))[:, None] + rng.normal(0, 0.01, (60, 3))
    rows = [",".join(f"{v:.5f}" for v in qi) + "," + ",".join(f"{v:.4f}" for v in xi) + f",{ti:.2f}"
            for qi, xi, ti in zip(np.degrees(q), x, T)]
    path.write_text("# tool_mm: 0, 0, 150\nq1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm,temp_C\n" + "\n".join(rows) + "\n")
    return path, T


def test_the_temperature_column_is_read(tmp_path):
    path, T = _points(tmp_path / "t.validation.csv", 0.0)
    assert np.allclose(read_points(path).temp_each_C, np.round(T, 2))
    assert main(["validate", str(path)]) == 0


@pytest.mark.parametrize("growth, found", [(40.0, True), (0.0, False)])
def test_the_arms_thermal_growth_is_named_from_the_points_temperature(tmp_path, capsys, growth, found):
    path, _ = _points(tmp_path / "t.validation.csv", growth)
    main(["calibrate", "--points", str(path), "--robot", "tx90", "--noise-um", "10"])
    said = capsys.readouterr()
    assert ("thermal_drift (temperature)" in said.out + said.err) == found
