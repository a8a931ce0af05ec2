"""The robot's own unmodelled error of the simulated robot (calibrate.robot_floor.RobotFloor, study --robot-floor-mm)."""
import numpy as np
import pytest

from rodlab.calibrate import resolve_robot
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.kinematics import ModelParams, ball_positions
from rodlab.calibrate.robot_floor import FLOOR_TOOL_MM, robot_floor


@pytest.fixture(scope="module")
def tx90():
    return resolve_robot("tx90")


def _poses(robot, n, seed):
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    return np.random.default_rng(seed).uniform(lo * 0.6, hi * 0.6, (n, robot.n))


def test_zero_floor_is_none_and_negative_is_refused(tx90):
    assert robot_floor(tx90, 0.0, 1) is None
    with pytest.raises(CalibrationError, match="robot_floor_mm"):
        robot_floor(tx90, -0.1, 1)


@pytest.mark.parametrize("floor_mm", [0.1, 0.263])
def test_floor_is_the_mean_rigid_tool_error_on_fresh_poses(tx90, floor_mm):
    f = robot_floor(tx90, floor_mm, 7)
    q = _poses(tx90, 500, 99)                       # not the poses it was sized on
    nominal = ModelParams.nominal(tx90, np.asarray(FLOOR_TOOL_MM, float))
    p0, _ = ball_positions(tx90, nominal, q)
    p1, _ = ball_positions(tx90, nominal, f.angles(q))
    assert np.mean(np.linalg.norm(p1.pW - p0.pW, axis=1)) == pytest.approx(floor_mm, rel=0.1)
    assert np.max(np.abs(f.angles(q) - q)) < np.deg2rad(0.1)     # small, smooth joint-angle errors


def test_floor_is_a_property_of_the_robot_not_of_the_pose(tx90):
    f = robot_floor(tx90, 0.263, 3)
    q = _poses(tx90, 5, 1)
    assert np.allclose(f.angles(q), robot_floor(tx90, 0.263, 3).angles(q))
    assert not np.allclose(f.angles(q), robot_floor(tx90, 0.263, 4).angles(q))
    # smooth: a 0.01 deg step of the commanded angles moves the error by far less than the error itself
    dq = np.deg2rad(0.01)
    assert np.max(np.abs((f.angles(q + dq) - q - dq) - (f.angles(q) - q))) < 0.05 * np.max(np.abs(f.angles(q) - q))
