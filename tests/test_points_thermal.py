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


def test_a_blank_temperature_or_time_cell_is_a_value_not_recorded(tmp_path, capsys):
    """A tracker's export leaves a cell empty where its weather station dropped out (a trial: one blank cell had
    refused the whole file): read as NaN, interpolated for the thermal test, which still finds the growth."""
    path, T = _points(tmp_path / "t.validation.csv", 40.0)
    lines = path.read_text().splitlines()
    for k in (5, 30):                                       # data rows 4 and 29: temperature not recorded
        lines[k] = lines[k].rsplit(",", 1)[0] + ","
    path.write_text("\n".join(lines) + "\n")
    pts = read_points(path)
    assert np.isnan(pts.temp_each_C).sum() == 2 and np.isfinite(pts.temp_each_C).sum() == 58
    assert pts.subset(np.arange(60) % 2 == 0).temp_each_C.shape == (30,)
    main(["calibrate", "--points", str(path), "--robot", "tx90", "--noise-um", "10"])
    said = capsys.readouterr()
    assert "thermal_drift (temperature)" in said.out + said.err
    assert "2 blank temp_C cell(s) interpolated" in said.out + said.err


def test_a_blank_coordinate_is_still_refused(tmp_path):
    from rodlab.calibrate.errors import CalibrationError
    path, _ = _points(tmp_path / "t.validation.csv", 0.0)
    lines = path.read_text().splitlines()
    cells = lines[3].split(",")
    cells[6] = ""                                           # x_mm of the second point
    lines[3] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(CalibrationError, match="line 4.*x_mm|x_mm.*line 4"):
        read_points(path)


def _drifting_points(path, pause_s: float):
    """60 poses of the nominal TX90 measured in two sittings ``pause_s`` apart; the instrument's zero moves by
    0.1 mm per hour along x (a tracker warming up), 10 um noise; each point's time in a time_s column."""
    robot = resolve_robot("tx90")
    rng = np.random.default_rng(11)
    p = ModelParams.nominal(robot, np.array([0.0, 0.0, 150.0]))
    q = rng.uniform(-1.0, 1.0, (60, 6)) * np.radians([90, 60, 70, 110, 60, 110])
    t = np.r_[np.arange(30) * 20.0, pause_s + np.arange(30) * 20.0]
    x = forward(p, q).p0 + np.c_[0.1 * t / 3600.0, 0 * t, 0 * t] + rng.normal(0, 0.01, (60, 3))
    rows = [",".join(f"{v:.5f}" for v in qi) + "," + ",".join(f"{v:.4f}" for v in xi) + f",{ti:.0f}"
            for qi, xi, ti in zip(np.degrees(q), x, t)]
    path.write_text("# tool_mm: 0, 0, 150\nq1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm,time_s\n" + "\n".join(rows) + "\n")
    return path


def test_the_drift_is_taken_over_the_points_time(tmp_path):
    """Two sittings four hours apart: the instrument's zero follows each point's time_s, a step at the pause that
    a quadratic in measurement order follows only in part; read over time it is named at `time` and explains
    more than it does over the measurement order."""
    from dataclasses import replace

    from rodlab.app.diagnose.points import diagnose_points
    from rodlab.calibrate.points import identify_points

    pts = read_points(_drifting_points(tmp_path / "d.validation.csv", 4 * 3600.0))
    assert np.isfinite(pts.time_each_s).all()
    robot = resolve_robot("tx90")
    res = identify_points(robot, pts, 0.01, fix_unidentifiable=True)
    def drift_share(p):
        return {f.where: f.explained_share for f in diagnose_points(robot, p, res, 0.01).findings
                if f.effect == "drift"}
    over_time, over_order = drift_share(pts), drift_share(replace(pts, time_each_s=None))
    assert set(over_time) == {"time"} and set(over_order) <= {"measurement order"}
    assert over_time["time"] > over_order.get("measurement order", 0.0) + 0.05


def test_calibrate_writes_each_points_residual(tmp_path, capsys):
    """--residuals: one row per point, its joint angles as read and its residual vector, whose rms is the fit's
    (a trial: the per-point residuals had been in no file)."""
    import csv
    path, _ = _points(tmp_path / "t.validation.csv", 40.0)
    out = tmp_path / "res.csv"
    main(["calibrate", "--points", str(path), "--robot", "tx90", "--noise-um", "10", "--residuals", str(out),
          "--json", str(tmp_path / "cal.json")])
    rows = list(csv.DictReader(out.read_text().splitlines()))
    assert len(rows) == 60 and rows[0]["row"] == "1"
    q = read_points(path).q_deg
    assert np.allclose([float(rows[5][f"q{i}"]) for i in range(1, 7)], q[5], atol=1e-6)
    d = np.array([[float(r[c]) for c in ("dx_mm", "dy_mm", "dz_mm")] for r in rows])
    assert np.allclose(np.linalg.norm(d, axis=1), [float(r["norm_mm"]) for r in rows], atol=2e-6)
    import json
    rms = json.loads((tmp_path / "cal.json").read_text())["residual_rms_mm"]
    assert np.sqrt(np.mean(d ** 2)) == pytest.approx(rms, rel=1e-3)


def test_a_points_files_names_reach_its_residuals(tmp_path):
    """A tracker's `name` column (kept, not read before) labels each point's row of --residuals, quoted where a
    name has a comma; subsets keep the names."""
    import csv
    path, _ = _points(tmp_path / "t.validation.csv", 0.0)
    lines = path.read_text().splitlines()
    lines[1] += ",name"
    lines[2:] = [f'{ln},"P{k}, wall"' for k, ln in enumerate(lines[2:], start=1)]
    path.write_text("\n".join(lines) + "\n")
    pts = read_points(path)
    assert pts.names[0] == "P1, wall" and pts.subset(np.arange(60) > 57).names == ("P59, wall", "P60, wall")
    out = tmp_path / "res.csv"
    main(["calibrate", "--points", str(path), "--robot", "tx90", "--noise-um", "10", "--residuals", str(out)])
    rows = list(csv.DictReader(out.read_text().splitlines()))
    assert [r["label"] for r in rows[:2]] == ["P1, wall", "P2, wall"]
