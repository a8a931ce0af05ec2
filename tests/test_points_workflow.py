"""Instrument points as a first-class workflow: the noise is an input, the trust verdict and exit codes match
campaign mode, and `rodlab diagnose --points` names joint-, direction- and order-dependent residuals."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.calibrate import FitOptions, ModelParams, resolve_robot, Rod
from rodlab.calibrate.kinematics import forward
from rodlab.app.cli.main import main


def _write_points(path, robot, seed, noise_mm=0.025, lost_motion_deg=0.0, n=120, sigma_column=None):
    """Tracker points of a truth robot (random geometric errors) at random poses in random order; optional
    lost motion of joint 1: the joint stops short by ``lost_motion_deg`` in the direction it came from."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.limits_deg[:, 0], robot.limits_deg[:, 1]
    q_deg = rng.uniform(np.maximum(lo, -150), np.minimum(hi, 150), (n, robot.n))
    nom = ModelParams.nominal(robot, np.array([30.0, 20.0, 150.0]), np.array([2500.0, -300.0, 400.0, 0.3, -0.2, 40]))
    truth = nom.with_(d=nom.d + rng.normal(0, 0.3, robot.n), a=nom.a + rng.normal(0, 0.3, robot.n),
                      alpha=nom.alpha + np.deg2rad(rng.normal(0, 0.02, robot.n)),
                      theta_offset=nom.theta_offset + np.deg2rad(rng.normal(0, 0.02, robot.n)))
    q_eff = q_deg.copy()
    step = np.sign(np.diff(q_deg[:, 0], prepend=q_deg[0, 0] - 1.0))
    q_eff[:, 0] -= lost_motion_deg * step
    sig = np.full((n, 3), noise_mm) if sigma_column is None else sigma_column(rng, n)
    x = forward(truth, np.deg2rad(q_eff)).pW + rng.normal(0, 1, (n, 3)) * sig
    if sigma_column is None:
        rows = "\n".join(",".join(f"{v:.6f}" for v in (*qq, *xx)) for qq, xx in zip(q_deg, x))
    else:
        rows = "\n".join(",".join(f"{v:.6f}" for v in (*qq, *xx, *ss)) for qq, xx, ss in zip(q_deg, x, sig))
    cols = ",".join([f"q{i + 1}" for i in range(robot.n)] + ["x_mm", "y_mm", "z_mm"] + (
        [] if sigma_column is None else ["sigma_x_mm", "sigma_y_mm", "sigma_z_mm"]))
    path.write_text("# simulated tracker points\n# tool_mm: 30, 20, 150\n# rod_mass_kg: 0\n# rod_com_T_mm: 0, 0, 0\n"
                    f"{cols}\n{rows}\n")
    return path


@pytest.fixture(scope="module")
def robot():
    return resolve_robot("r2000ic165f")


def test_clean_tracker_points_are_trusted_with_the_tracker_noise(tmp_path, capsys, robot):
    pts = _write_points(tmp_path / "p.validation.csv", robot, seed=1)
    assert main(["calibrate", "--points", str(pts), "--robot", "r2000ic165f", "--fix-unidentifiable",
                 "--json", str(tmp_path / "cal.json")]) == 0
    out = capsys.readouterr()
    assert "residuals consistent with noise" in out.out and "instrument 25.0 um per coordinate" in out.out
    assert "NOT TRUSTED" not in out.err
    # the same points judged against the MultiCal device's 3 um: the model is not complete at that noise, but the
    # calibration still predicts held-out points far better than nominal: usable, with the completeness caution
    assert main(["calibrate", "--points", str(pts), "--robot", "r2000ic165f", "--fix-unidentifiable",
                 "--noise-um", "3"]) == 0
    out = capsys.readouterr()
    assert "complete? no" in out.out and "usable? yes" in out.out and "verdict: TRUSTED" in out.out
    assert "NOT TRUSTED" not in out.err and "the model is incomplete" in out.err and "check --noise-um" in out.err
    assert "diagnose --campaign" not in out.err


def test_lost_motion_is_an_incomplete_model_diagnosed_at_its_joint(tmp_path, capsys, robot):
    """Lost motion the model cannot carry: the calibration still predicts better than nominal (usable, exit 0),
    and the completeness statement names what is left out, with the diagnosis's finding at joint 1."""
    pts = _write_points(tmp_path / "p.validation.csv", robot, seed=2, lost_motion_deg=0.01)
    assert main(["calibrate", "--points", str(pts), "--robot", "r2000ic165f", "--json", str(tmp_path / "c.json")]) == 0
    io = capsys.readouterr()
    assert "complete? no" in io.out and "the model is incomplete" in io.err and "lost_motion (joint 1)" in io.err
    import json
    cal = json.loads((tmp_path / "c.json").read_text())
    assert cal["trusted"] and cal["fit"]["completeness"]["verdict"] == "incomplete"
    assert cal["fit"]["prediction"]["source"] == "cross_validation" and cal["fit"]["prediction"]["clearly_better"]
    assert main(["diagnose", "--points", str(pts), "--robot", "r2000ic165f", "--json",
                 str(tmp_path / "d.json"), "--report", str(tmp_path / "d.html")]) == 0
    html = (tmp_path / "d.html").read_text()
    assert "Diagnosis of instrument points" in html and "lost_motion" in html and "Workspace regions" in html
    import json
    d = json.loads((tmp_path / "d.json").read_text())
    assert d["findings"][0]["effect"] == "lost_motion" and d["findings"][0]["where"] == "joint 1"
    assert not d["consistent"]


@pytest.mark.parametrize("seed", [3, 4, 5, 6])
def test_noise_only_points_have_no_findings(tmp_path, robot, seed):
    """No false alarm: points with nothing but the stated noise give no finding (p < 1e-3 per candidate)."""
    from rodlab.calibrate import Observations, identify, read_points
    from rodlab.app.diagnose.points import diagnose_points
    path = _write_points(tmp_path / "p.validation.csv", robot, seed=seed)
    pts = read_points(path, robot.n)
    obs = Observations(np.deg2rad(pts.q_deg), pts.x_W_mm, np.zeros_like(pts.x_W_mm))
    res = identify(robot, obs, Rod.rigid(pts.tool_mm),
                   options=FitOptions(freed={"tool_y"}, fix_unidentifiable=True, find_tool=True, expected_noise_mm=0.025))
    diag = diagnose_points(robot, pts, res, 0.025)
    assert diag.findings == () and diag.consistent, diag.summary()


def test_points_that_cannot_identify_speak_of_poses(tmp_path, capsys, robot):
    """A refusal of point data speaks of poses and workspace, not of clamping positions."""
    pts = _write_points(tmp_path / "p.validation.csv", robot, seed=7, n=40)
    text = pts.read_text().splitlines()
    body = [line.split(",") for line in text[5:]]
    for row in body:
        row[1] = "10.000000"                           # joint 2 never moves
    pts.write_text("\n".join(text[:5] + [",".join(r) for r in body]) + "\n")
    assert main(["calibrate", "--points", str(pts), "--robot", "r2000ic165f", "--strict"]) == 2
    err = capsys.readouterr().err
    assert "these points cannot identify" in err and "poses spread over the workspace" in err
    assert "clamping" not in err


def _far_and_near(rng, n):
    """A tracker's per-point uncertainty: a third of the points far and noisy (80 um), the rest near (8 um)."""
    s = np.full((n, 3), 0.008)
    s[rng.permutation(n)[: n // 3]] = 0.080
    return s


def test_per_point_uncertainty_columns_are_the_noise_model(tmp_path, capsys, robot):
    """Points whose noise differs point by point (stated in sigma_*_mm columns) are judged by those sigmas:
    consistent with noise; one scalar level (their near-point 8 um) calls the same residuals not noise."""
    from rodlab.calibrate import read_points
    from rodlab.calibrate.points import identify_points, stated_noise_mm
    path = _write_points(tmp_path / "p.validation.csv", robot, seed=11, n=150, sigma_column=_far_and_near)
    pts, noise = stated_noise_mm(read_points(path, robot.n), None)
    assert pts.sigma_mm.shape == (150, 3) and noise == pytest.approx(np.sqrt(np.mean(pts.sigma_mm ** 2)))
    stated = identify_points(robot, pts, noise, fix_unidentifiable=True).residual_check
    assert not stated.missing and 0.7 < stated.reduced < 1.3
    scalar_pts, scalar = stated_noise_mm(pts, 0.008)
    assert scalar_pts.sigma_mm is None and scalar == 0.008
    assert identify_points(robot, scalar_pts, scalar, fix_unidentifiable=True).residual_check.missing
    assert main(["calibrate", "--points", str(path), "--robot", "r2000ic165f", "--fix-unidentifiable"]) == 0
    assert "residuals consistent with noise" in capsys.readouterr().out


def test_per_point_uncertainty_columns_are_checked(tmp_path, capsys, robot):
    path = _write_points(tmp_path / "p.validation.csv", robot, seed=12, n=20, sigma_column=_far_and_near)
    text = path.read_text()
    (tmp_path / "partial.csv").write_text(text.replace(",sigma_z_mm", "").replace(",0.080000\n", "\n")
                                          .replace(",0.008000\n", "\n"))
    assert main(["calibrate", "--points", str(tmp_path / "partial.csv"), "--robot", "r2000ic165f"]) == 2
    err = capsys.readouterr().err
    assert "sigma_z_mm" in err and "partial.csv" in err
    lines = text.splitlines()
    lines[-1] = ",".join(lines[-1].split(",")[:-1] + ["0"])
    (tmp_path / "zero.csv").write_text("\n".join(lines) + "\n")
    assert main(["calibrate", "--points", str(tmp_path / "zero.csv"), "--robot", "r2000ic165f"]) == 2
    err = capsys.readouterr().err
    assert f"line {len(lines)}" in err and "sigma_z_mm" in err and "> 0" in err
