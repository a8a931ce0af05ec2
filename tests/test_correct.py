"""`rodlab correct`: TCP targets -> joint commands that put the calibrated robot on target, and the corrected
targets for a controller that keeps its nominal model, round-tripping through the calibrated forward
kinematics within 1 um; and the export's check of the analytic-IK assumptions the calibration breaks."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli.main import main
from rodlab.calibrate import ModelParams, ball_positions, read_points, resolve_robot
from rodlab.calibrate.correct import correct_targets, ik_assumptions
from rodlab.calibrate.ik import solve_ik_positions

DATA = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "jacobi2025"


@pytest.fixture(scope="module")
def ur5():
    return resolve_robot("ur5")


def _models(robot):
    nominal = ModelParams.nominal(robot, np.array([0.0, 0.0, 40.0]), np.array([100.0, -50.0, 20.0, 0.1, -0.2, 30.0]))
    rng = np.random.default_rng(3)
    calibrated = nominal.with_(a=nominal.a + rng.normal(0, 0.3, robot.n), d=nominal.d + rng.normal(0, 0.3, robot.n),
                               alpha=nominal.alpha + np.deg2rad(rng.normal(0, 0.03, robot.n)),
                               beta=nominal.beta + np.deg2rad(np.r_[0, 0.02, -0.01, 0, 0, 0]),
                               theta_offset=nominal.theta_offset + np.deg2rad(rng.normal(0, 0.03, robot.n)),
                               c=np.r_[0, 2e-5, 1e-5, 0, 0, 0])
    return nominal, calibrated


def _tcp(robot, p, q):
    return ball_positions(robot, p, np.atleast_2d(q))[0].pW


def test_commands_and_corrected_targets_round_trip_within_a_micrometre(ur5):
    nominal, calibrated = _models(ur5)
    rng = np.random.default_rng(1)
    program = np.deg2rad(rng.uniform(-60, 60, (40, 6)) + np.array([0, -60, 60, -60, 90, 0]))
    targets = _tcp(ur5, nominal, program) + rng.normal(0, 1.0, (40, 3))
    corr = correct_targets(ur5, calibrated, nominal, targets, program)
    assert corr.ok.all()
    assert np.abs(np.linalg.norm(_tcp(ur5, calibrated, corr.q_rad) - targets, axis=1)).max() < 1e-3   # < 1 um
    # the corrected targets are the nominal model's TCP pose at the commands: a nominal controller given them
    # (position and the flange orientation) is at a solution there, so the calibrated robot is on target
    from rodlab.core.frames import pose_to_matrix
    fr = ball_positions(ur5, nominal, corr.q_rad)[0]
    assert np.abs(fr.pW - corr.corrected_mm).max() < 1e-9
    R = np.einsum("ij,mjk->mik", fr.R_W0, fr.T[:, 6, :3, :3])
    assert np.abs(np.array([pose_to_matrix(np.r_[0, 0, 0, a])[:3, :3] for a in corr.corrected_abc_deg]) - R).max() < 1e-9
    back = solve_ik_positions(ur5, nominal, corr.corrected_mm, corr.q_rad, pos_tol_mm=1e-5, pull=False)
    assert back.ok.all() and np.abs(back.q_rad - corr.q_rad).max() < 1e-9
    assert np.linalg.norm(_tcp(ur5, calibrated, back.q_rad) - targets, axis=1).max() < 1e-3
    # what the correction removes: the nominal program's joints put the calibrated TCP off by the model difference
    nom_q = solve_ik_positions(ur5, nominal, targets, program, pos_tol_mm=1e-5).q_rad
    miss = np.linalg.norm(_tcp(ur5, calibrated, nom_q) - targets, axis=1)
    assert np.allclose(corr.uncorrected_mm, miss, atol=1e-6) and miss.mean() > 0.3


def test_ik_assumptions_measure_the_calibrated_deviation(ur5):
    nominal, _ = _models(ur5)
    assert all(d.effect_mm < 1e-9 for d in ik_assumptions(ur5, nominal, nominal))
    kinds = {d.joints: d.assumption for d in ik_assumptions(ur5, nominal, nominal)}
    assert kinds[(2, 3)] == kinds[(3, 4)] == "parallel" and kinds[(1, 2)] == "intersecting"
    tilted = nominal.with_(alpha=nominal.alpha + np.deg2rad(np.r_[0, 0, 0.01, 0, 0, 0]),
                           a=nominal.a + np.r_[0.5, 0, 0, 0, 0, 0])
    dev = {d.joints: d for d in ik_assumptions(ur5, tilted, nominal)}
    assert dev[(3, 4)].angle_deg == pytest.approx(0.01, rel=1e-6) and dev[(2, 3)].angle_deg < 1e-9
    assert dev[(1, 2)].distance_mm == pytest.approx(0.5, rel=1e-6)


def _calibrate_ur5(tmp_path):
    """``rodlab calibrate`` on every 4th point of the UR5 grid, validated on the random set: the result file."""
    lines = (DATA / "ur5_grid.validation.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [next(ln for ln in lines if ln.startswith("q1"))]
    rows = [ln for ln in lines if ln and not ln.startswith(("#", "q1"))][::4]
    fit = tmp_path / "fit.validation.csv"
    fit.write_text("\n".join(head + rows) + "\n")
    cal = tmp_path / "cal.json"
    assert main(["calibrate", "--points", str(fit), "--robot", "ur5", "--validate",
                 str(DATA / "ur5_random.validation.csv"), "--json", str(cal)]) == 0
    return cal


def test_cli_correct_and_the_export_warning(tmp_path, capsys):
    """The UR5 tracker data: calibrate, then the 20 random poses' measured positions as targets with their
    recorded joints as the program: the commands round-trip within 1 um and stay next to the recorded joints
    (the calibrated model explains those measurements to ~0.1 mm); export warns of the broken parallel axes."""
    cal = _calibrate_ur5(tmp_path)
    from rodlab.calibrate.result import calibrated_params, read_calibration
    pts = read_points(DATA / "ur5_random.validation.csv", 6)
    targets = tmp_path / "t.targets.csv"
    targets.write_text("# the random poses\nx_mm,y_mm,z_mm,q1,q2,q3,q4,q5,q6\n" + "\n".join(
        ",".join(f"{v:.6f}" for v in (*x, *q)) for q, x in zip(pts.q_deg, pts.x_W_mm)) + "\n")
    out = tmp_path / "commands.csv"
    capsys.readouterr()
    assert main(["correct", str(cal), str(targets), "-o", str(out)]) == 0
    assert "IK residual max" in capsys.readouterr().out
    table = list(csv.DictReader(ln for ln in out.read_text().splitlines() if not ln.startswith("#")))
    assert len(table) == 20 and all(r["ok"] == "1" for r in table)
    q_cmd = np.deg2rad([[float(r[f"q{i}"]) for i in range(1, 7)] for r in table])
    params = calibrated_params(resolve_robot("ur5"), read_calibration(cal))
    reached = ball_positions(resolve_robot("ur5"), params, q_cmd)[0].pW
    assert np.linalg.norm(reached - pts.x_W_mm, axis=1).max() < 1e-3
    assert np.abs(np.rad2deg(q_cmd) - pts.q_deg).max() < 0.1
    pred = json.loads(cal.read_text())["fit"]["prediction"]["mean_mm"]
    assert float(table[0]["predicted_mm"]) == pytest.approx(pred, abs=1e-4)
    assert main(["export", str(cal), "-o", str(tmp_path / "exp")]) == 0
    err = capsys.readouterr().err
    assert "joints 2 and 3 are parallel in the nominal model" in err and "rodlab correct" in err


def test_bad_targets_are_refused_with_the_line(tmp_path, capsys):
    cal = tmp_path / "cal.json"
    bad = tmp_path / "bad.targets.csv"
    bad.write_text("x_mm,y_mm,z_mm\n1,2,3\n1,x,3\n")
    nominal = resolve_robot("ur5")
    from rodlab.calibrate.targets import read_targets
    from rodlab.calibrate import CalibrationError
    with pytest.raises(CalibrationError) as e:
        read_targets(bad, nominal.n)
    assert e.value.line == 3 and e.value.key == "y_mm"
    assert main(["correct", str(cal), str(bad), "-o", str(tmp_path / "o.csv")]) == 2
    assert not (tmp_path / "o.csv").exists()


def _flange_poses(robot, params, q, R_tool=None):
    from rodlab.calibrate.ik_pose import tcp_poses
    return tcp_poses(robot, params, q, R_tool)


def test_pose_targets_round_trip_within_a_micrometre_and_a_microradian(ur5):
    """Pose targets (position and the tool frame's orientation, the tool turned 30 deg on the flange) -> 6-D IK
    commands -> calibrated forward kinematics: within 1 um and 1 urad; the corrected target is the nominal model's
    tool pose at the commands (a nominal pose IK of it returns them); the nominal program misses in both."""
    from rodlab.calibrate.correct import correct_poses
    from rodlab.calibrate.ik_pose import rotation_angle, solve_ik_poses
    from rodlab.core.frames import matrix_to_pose, rotation_from_abc
    nominal, calibrated = _models(ur5)
    rng = np.random.default_rng(2)
    program = np.deg2rad(rng.uniform(-40, 40, (30, 6)) + np.array([0, -80, 90, -60, 90, 0]))  # elbow bent, no wrist flip
    R_tool = rotation_from_abc([0.0, 30.0, 10.0])
    p, R = _flange_poses(ur5, nominal, program, R_tool)
    abc = np.array([matrix_to_pose(np.block([[r, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))[3:]
                    for r in R])
    corr = correct_poses(ur5, calibrated, nominal, p, abc, program, R_tool)
    assert corr.ok.all()
    p_cal, R_cal = _flange_poses(ur5, calibrated, corr.q_rad, R_tool)
    assert np.linalg.norm(p_cal - p, axis=1).max() < 1e-3                                 # < 1 um
    assert rotation_angle(R_cal @ np.swapaxes(R, 1, 2)).max() < 1e-6                       # < 1 urad
    assert corr.residual_mm.max() < 1e-3 and corr.residual_rad.max() < 1e-6
    p_nom, R_nom = _flange_poses(ur5, nominal, corr.q_rad, R_tool)
    assert np.abs(p_nom - corr.corrected_mm).max() < 1e-9
    R_corr = np.array([rotation_from_abc(a) for a in corr.corrected_abc_deg])
    assert rotation_angle(R_corr @ np.swapaxes(R_nom, 1, 2)).max() < 1e-9
    back = solve_ik_poses(ur5, nominal, corr.corrected_mm, R_corr, corr.q_rad, R_tool)
    assert back.ok.all() and np.abs(back.q_rad - corr.q_rad).max() < 1e-7
    assert corr.uncorrected_mm.mean() > 0.3 and corr.uncorrected_rad.mean() > 1e-4        # what it removes
    assert np.rad2deg(np.abs(corr.q_rad - program)).max() < 2.0                          # the program's branch


def test_cli_pose_targets_and_their_refusals(tmp_path, capsys):
    """A UR5 calibration; the calibrated robot's tool poses at the 20 recorded random configurations as pose
    targets: the commands come back to those joints and the calibrated FK of the written commands is on the
    targets within 1 um / 1 urad. An unreachable pose, a quaternion column and a partial orientation are refused
    with the file and line, exit 2, and no output file."""
    from rodlab.calibrate.result import calibrated_params, read_calibration
    from rodlab.calibrate.ik_pose import rotation_angle
    from rodlab.core.frames import matrix_to_pose, rotation_from_abc
    cal = _calibrate_ur5(tmp_path)
    robot = resolve_robot("ur5")
    params = calibrated_params(robot, read_calibration(cal))
    pts = read_points(DATA / "ur5_random.validation.csv", 6)
    R_tool = rotation_from_abc([0.0, 0.0, 45.0])
    p, R = _flange_poses(robot, params, np.deg2rad(pts.q_deg), R_tool)
    abc = [matrix_to_pose(np.block([[r, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))[3:] for r in R]
    seeds = pts.q_deg + 3.0                                         # the program: near, not at, the solution
    targets = tmp_path / "p.targets.csv"
    targets.write_text("x_mm,y_mm,z_mm,a_deg,b_deg,c_deg,q1,q2,q3,q4,q5,q6\n" + "\n".join(
        ",".join(f"{v:.9f}" for v in (*x, *a, *q)) for x, a, q in zip(p, abc, seeds)) + "\n")
    out = tmp_path / "commands.csv"
    capsys.readouterr()
    assert main(["correct", str(cal), str(targets), "--tool-abc", "0,0,45", "-o", str(out)]) == 0
    assert "urad" in capsys.readouterr().out
    table = list(csv.DictReader(ln for ln in out.read_text().splitlines() if not ln.startswith("#")))
    assert len(table) == 20 and all(r["ok"] == "1" for r in table)
    q_cmd = np.deg2rad([[float(r[f"q{i}"]) for i in range(1, 7)] for r in table])
    assert np.abs(np.rad2deg(q_cmd) - pts.q_deg).max() < 1e-4
    p_cmd, R_cmd = _flange_poses(robot, params, q_cmd, R_tool)
    assert np.linalg.norm(p_cmd - p, axis=1).max() < 1e-3
    assert rotation_angle(R_cmd @ np.swapaxes(R, 1, 2)).max() < 1e-6
    assert max(float(r["residual_urad"]) for r in table) < 1.0
    bad = tmp_path / "bad.targets.csv"
    cases = {"x_mm,y_mm,z_mm,a_deg,b_deg,c_deg\n300,100,400,180,0,0\n5000,0,0,180,0,0\n": ("line 3", "not reachable"),
             "x_mm,y_mm,z_mm,qw,qx,qy,qz\n300,100,400,1,0,0,0\n": ("line 1", "a_deg, b_deg, c_deg"),
             "x_mm,y_mm,z_mm,a_deg,b_deg\n300,100,400,180,0\n": ("line 1", "needs all of")}
    for text, (where, what) in cases.items():
        bad.write_text(text)
        o = tmp_path / "o.csv"
        assert main(["correct", str(cal), str(bad), "-o", str(o)]) == 2
        err = capsys.readouterr().err
        assert str(bad.name) in err and where in err and what in err, err
        assert not o.exists()


def test_a_pose_target_that_flips_the_wrist_is_warned_about(ur5, caplog):
    """A target orientation in another frame (turned 180 deg) is reached only by leaving the program's
    configuration: the commands are still exact, and the target is named in a warning."""
    import logging

    from rodlab.calibrate.correct import correct_poses
    from rodlab.core.frames import matrix_to_pose
    nominal, calibrated = _models(ur5)
    program = np.deg2rad(np.array([[10.0, -80.0, 90.0, -60.0, 90.0, 0.0], [-10.0, -70.0, 80.0, -50.0, 80.0, 20.0]]))
    p, R = _flange_poses(ur5, nominal, program)
    abc = np.array([matrix_to_pose(np.block([[r, np.zeros((3, 1))], [np.zeros((1, 3)), np.ones((1, 1))]]))[3:]
                    for r in R])
    abc[1, 0] += 180.0                                                   # the second target's frame turned
    with caplog.at_level(logging.WARNING, logger="rodlab.calibrate.correct"):
        corr = correct_poses(ur5, calibrated, nominal, p, abc, program)
    assert corr.residual_mm.max() < 1e-3
    warned = [r.getMessage() for r in caplog.records if "leave the program's configuration" in r.getMessage()]
    assert len(warned) == 1 and warned[0].startswith("target 2")


def _random_targets(tmp_path, k: int):
    """A targets file of the UR5 random set's first ``k`` measured positions with their recorded joints."""
    pts = read_points(DATA / "ur5_random.validation.csv", 6)
    rows = [(*x, *q) for q, x in zip(pts.q_deg[:k], pts.x_W_mm[:k])]
    targets = tmp_path / "t.targets.csv"
    targets.write_text("x_mm,y_mm,z_mm,q1,q2,q3,q4,q5,q6\n" + "\n".join(",".join(f"{v:.6f}" for v in r) for r in rows)
                       + "\n")
    return targets


def test_each_target_gets_the_uncertainty_its_pose_has_from_the_parameters(tmp_path, capsys):
    """`predicted_mm` is the calibration's held-out mean, one number; `param_sd_mm` is each target's own: the
    identified parameters' covariance (the result's fit.correlation) through the TCP Jacobian at its commands: it
    differs from target to target, matches a Monte Carlo of the parameters in the file's own units, and is empty
    for a result written without the correlation (an IRB 4600 trial: the column had been the held-out mean copied
    to every target; the new one follows the true per-target error there, correlation 0.89)."""
    from dataclasses import replace

    from rodlab.calibrate.result import calibrated_params, read_calibration
    cal = _calibrate_ur5(tmp_path)
    targets = _random_targets(tmp_path, 5)
    out = tmp_path / "commands.csv"
    assert main(["correct", str(cal), str(targets), "-o", str(out)]) == 0
    assert "its parameters pin the targets to" in capsys.readouterr().out
    table = list(csv.DictReader(ln for ln in out.read_text().splitlines() if not ln.startswith("#")))
    sd = np.array([float(r["param_sd_mm"]) for r in table])
    assert np.all(sd > 0) and np.ptp(sd) > 0 and np.all(sd < 1.0)
    robot, c = resolve_robot("ur5"), read_calibration(cal)
    # Monte Carlo in the file's own units (deg, mm, rad/(N m)) through calibrated_params: independent of the
    # internal units the propagation uses
    q = np.deg2rad([[float(r[f"q{i}"]) for i in range(1, 7)] for r in table])
    names = [n for n in c.correlation_names if not n.startswith(("tool_", "fixture_"))]
    ix = [c.correlation_names.index(n) for n in names]
    sig = np.array([c.parameters[n].sigma for n in names])
    draws = np.random.default_rng(0).multivariate_normal(np.zeros(len(names)),
                                                         c.correlation[np.ix_(ix, ix)] * np.outer(sig, sig), 400)
    p0 = ball_positions(robot, calibrated_params(robot, c), q)[0].pW
    spread = np.zeros(len(q))
    for d in draws:
        moved = {n: replace(c.parameters[n], value=c.parameters[n].value + v) for n, v in zip(names, d)}
        pw = ball_positions(robot, calibrated_params(robot, replace(c, parameters={**c.parameters, **moved})), q)[0].pW
        spread += ((pw - p0) ** 2).sum(axis=1)
    assert sd == pytest.approx(np.sqrt(spread / len(draws)), rel=0.15)
    data = json.loads(cal.read_text())
    del data["fit"]["correlation"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    assert main(["correct", str(old), str(targets), "-o", str(tmp_path / "c2.csv")]) == 0
    t2 = list(csv.DictReader(ln for ln in (tmp_path / "c2.csv").read_text().splitlines() if not ln.startswith("#")))
    assert all(r["param_sd_mm"] == "" for r in t2)


def test_a_parameter_the_data_do_not_see_is_unbounded_only_where_it_moves_the_tcp(tmp_path, capsys):
    """A result whose dtheta_6 has no sigma (null: a direction the data did not see): the targets' uncertainty is
    unbounded where that twist moves the TCP (a production tool off joint 6's axis) and unchanged where it does
    not (a tool on the axis); it had been infinite for every target whatever the tool."""
    cal = _calibrate_ur5(tmp_path)
    targets = _random_targets(tmp_path, 4)
    data = json.loads(cal.read_text())
    corr = data["fit"]["correlation"]
    n = len(corr["names"])
    corr["names"].append("dtheta_6")
    corr["matrix"] = [row + [0.0] for row in corr["matrix"]] + [[0.0] * n + [1.0]]
    data["parameters"]["dtheta_6"].update(sigma=None, status="identified")
    unseen = tmp_path / "unseen.json"
    unseen.write_text(json.dumps(data))

    def sd_of(path, tool):
        out = tmp_path / f"{path.stem}-{tool.replace(',', '_')}.csv"
        assert main(["correct", str(path), str(targets), "--tool", tool, "-o", str(out)]) == 0
        table = list(csv.DictReader(ln for ln in out.read_text().splitlines() if not ln.startswith("#")))
        return np.array([float(r["param_sd_mm"]) for r in table]), capsys.readouterr().out

    on_axis, off_axis = "0,0,120", "40,0,120"
    sd_seen, _ = sd_of(cal, on_axis)
    sd_unseen, said = sd_of(unseen, on_axis)
    assert np.all(np.isfinite(sd_unseen)) and sd_unseen == pytest.approx(sd_seen, rel=1e-9)
    assert "pin the targets to" in said and "unbounded" not in said
    sd_off, said = sd_of(unseen, off_axis)
    assert np.all(np.isinf(sd_off)) and "unbounded (param_sd_mm inf)" in said
    assert np.all(np.isfinite(sd_of(cal, off_axis)[0]))
