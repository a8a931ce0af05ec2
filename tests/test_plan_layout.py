"""``rodlab plan`` plans for the robot where it stands: ``--base`` (or ``--calibration``'s base) puts the planned
angles' ball on every datum point of that layout, without it the standard layout is assumed with a warning; every
planned rod leaves the ball from the device's open side (new-user trial: a KR16 standing elsewhere got angles that
missed the datums by 0.5-1 m, and half the rods pointed down into the sensors)."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli import main
from rodlab.calibrate import Rod, resolve_robot
from rodlab.calibrate.campaign import write_fixture
from rodlab.calibrate.kinematics import ModelParams, ball_positions
from rodlab.calibrate.plan import ROD_ANGLE_MAX_DEG, rod_angle_deg
from rodlab.calibrate.simulate import standard_base, standard_fixture
from rodlab.core.calc import calc_rod_compliance
from rodlab.core.compliance import write_compliance
from rodlab.core.design_io import resolve_design
from rodlab.core.frames import matrix_to_pose, pose_to_matrix

ROBOT = resolve_robot("tx90")


@pytest.fixture(scope="module")
def layout(tmp_path_factory):
    """A fixture in {W} and a robot standing 150 mm aside and turned 20 deg from the standard layout."""
    folder = tmp_path_factory.mktemp("plan")
    fix = standard_fixture()
    write_fixture(fix, folder / "f.fixture.json")
    rod = calc_rod_compliance(resolve_design("rod1"))
    write_compliance(rod, folder / "rod.compliance.json")
    moved = pose_to_matrix([0.0, 150.0, 0.0, 0.0, 0.0, 20.0]) @ pose_to_matrix(standard_base())
    return folder, fix, rod, matrix_to_pose(moved)


def _planned(path) -> dict:
    rows = np.loadtxt(path, delimiter=",", skiprows=1)
    return {int(j): np.deg2rad(rows[rows[:, 0] == j, 2:]) for j in np.unique(rows[:, 0])}


def _misses_mm(fix, rod, base, planned) -> np.ndarray:
    p = ModelParams.nominal(ROBOT, rod.tool_mm, base=base)
    out = []
    for j, q in planned.items():
        fr, _ = ball_positions(ROBOT, p, q, Rod.of(rod))
        out.append(np.linalg.norm(fr.pW - fix.transform(j)[:3, 3], axis=1))
    return np.concatenate(out)


def test_the_base_given_is_where_the_planned_ball_reaches_the_datums(layout, capsys):
    folder, fix, rod, base = layout
    out = folder / "plan.csv"
    assert main(["plan", "--fixture", str(folder / "f.fixture.json"), "--rod", str(folder / "rod.compliance.json"),
                 "--base=" + ",".join(f"{v:.6f}" for v in base), "-o", str(out)]) == 0
    assert "standard layout is assumed" not in capsys.readouterr().err
    planned = _planned(out)
    assert _misses_mm(fix, rod, base, planned).max() < 0.05
    assert _misses_mm(fix, rod, standard_base(), planned).min() > 10.0         # the standard layout would miss
    p = ModelParams.nominal(ROBOT, rod.tool_mm, base=base)
    for j, q in planned.items():
        assert np.all(rod_angle_deg(p, q, fix.transform(j)) <= ROD_ANGLE_MAX_DEG)


def test_the_base_from_a_calibration_result_and_the_warning_without_one(layout, tmp_path, capsys):
    folder, fix, rod, base = layout
    cal = {"format": "rodlab.calibration/1", "robot": "tx90", "compensation": "calc", "trusted": True,
           "residual_rms_mm": 0.003,
           "parameters": {k: {"value": float(v), "sigma": 0.01, "unit": "mm" if i < 3 else "deg",
                              "status": "identified"}
                          for i, (k, v) in enumerate(zip(("base_x", "base_y", "base_z", "base_a", "base_b", "base_c"),
                                                         base))}}
    (tmp_path / "cal.json").write_text(json.dumps(cal))
    args = ["plan", "--fixture", str(folder / "f.fixture.json"), "--rod", str(folder / "rod.compliance.json")]
    assert main(args + ["--calibration", str(tmp_path / "cal.json"), "-o", str(tmp_path / "a.csv")]) == 0
    assert _misses_mm(fix, rod, base, _planned(tmp_path / "a.csv")).max() < 0.05
    capsys.readouterr()
    assert main(args + ["-o", str(tmp_path / "b.csv")]) == 0
    assert "standard layout is assumed" in capsys.readouterr().err
    assert _misses_mm(fix, rod, standard_base(), _planned(tmp_path / "b.csv")).max() < 0.05


@pytest.mark.parametrize("gamma", [135.0, 180.0])
def test_a_rod_bent_otherwise_leaves_the_ball_along_its_own_pipe(layout, tmp_path, gamma):
    """The open-side rule follows pipe II of the rod given (a review found -x of the flange taken for every rod:
    a straight rod's plan pointed into the sensors)."""
    from rodlab.core.design_io import load_design
    folder, fix, _, base = layout
    text = Path(resolve_design("rod1").source).read_text()
    path = tmp_path / "g.rod.toml"
    path.write_text(re.sub(r"(?m)^gamma_deg = .*$", f"gamma_deg = {gamma}", text))
    d = load_design(path)
    assert d.gamma_deg == gamma
    out = tmp_path / "plan.csv"
    assert main(["plan", "--fixture", str(folder / "f.fixture.json"), "--rod", str(path),
                 "--base=" + ",".join(f"{v:.6f}" for v in base), "-o", str(out)]) == 0
    p = ModelParams.nominal(ROBOT, d.tool_mm, base=base)
    for j, q in _planned(out).items():
        assert np.all(rod_angle_deg(p, q, fix.transform(j), -d.pipe_II_direction) <= ROD_ANGLE_MAX_DEG + 1e-9)


def test_planned_poses_keep_off_the_joint_limits_and_above_the_floor(layout, tmp_path):
    """An IRB 4600 trial's plan had joints exactly on their hard limits (q3 = -170.0000 of [-170, 170]) and elbows
    below the base: every planned joint keeps 5 deg inside its limits by default (and --limit-margin-deg 0 may
    reach them), and with --floor-mm every joint origin stays above the floor."""
    folder, fix, rod, base = layout
    args = ["plan", "--fixture", str(folder / "f.fixture.json"), "--rod", str(folder / "rod.compliance.json"),
            "--base=" + ",".join(f"{v:.6f}" for v in base)]
    assert main([*args, "-o", str(tmp_path / "p.csv")]) == 0
    q = np.rad2deg(np.concatenate(list(_planned(tmp_path / "p.csv").values())))
    lim = ROBOT.limits_deg
    assert np.all(q >= lim[:, 0] + 5.0 - 1e-3) and np.all(q <= lim[:, 1] - 5.0 + 1e-3)
    assert main([*args, "--floor-mm", "-100", "-o", str(tmp_path / "f.csv")]) == 0
    qf = np.concatenate(list(_planned(tmp_path / "f.csv").values()))
    fr, _ = ball_positions(ROBOT, ModelParams.nominal(ROBOT, rod.tool_mm, base=base), qf, Rod.of(rod))
    assert np.all(fr.o_prev[:, 1:, 2] >= -100.0)
    assert main([*args, "--limit-margin-deg", "0", "-o", str(tmp_path / "z.csv")]) == 0


def test_a_floor_no_pose_clears_is_refused_with_the_reason(layout, capsys):
    folder, fix, rod, base = layout
    code = main(["plan", "--fixture", str(folder / "f.fixture.json"), "--rod", str(folder / "rod.compliance.json"),
                 "--base=" + ",".join(f"{v:.6f}" for v in base), "--floor-mm", "5000"])
    err = capsys.readouterr().err
    assert code == 2 and "with every joint above 5000 mm" in err and "the floor" in err
