"""Periodic joint errors (``--joint-harmonics``): the model term, its Jacobian, known-truth recovery from instrument
points, the result file (rodlab.calibration/2) and its exports."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab.calibrate import ModelParams, resolve_robot, result_dict, write_result
from rodlab.calibrate.result import calibrated_params, read_calibration
from rodlab.calibrate.points_file import PointSet
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.jacobian import position_jacobian
from rodlab.calibrate.kinematics import HARMONICS, ball_positions, forward, harmonic_reference
from rodlab.calibrate.params import apply, catalogue
from rodlab.calibrate.points import identify_points
from rodlab.calibrate.simulate import random_truth
from rodlab.calibrate.validate import validate

TOOL = np.array([15.0, 5.0, 120.0])
#: joint 4's error [deg]: h1s, h1c, h2s, h2c
H4_DEG = np.array([0.012, -0.009, 0.006, 0.004])


@pytest.fixture(scope="module")
def ur5():
    return resolve_robot("ur5")


def _truth(robot, seed=2):
    truth = random_truth(robot, TOOL, np.random.default_rng(seed))
    h = np.zeros((robot.n, 4))
    h[3] = np.deg2rad(H4_DEG)
    return truth.with_(base=np.array([800.0, -200.0, 50.0, 0.4, -0.3, 25.0]), h=h)


def _points(robot, truth, n, seed, noise_mm=0.005) -> PointSet:
    rng = np.random.default_rng(seed)
    q = rng.uniform(-170, 170, (n, robot.n))
    x = ball_positions(robot, truth, np.deg2rad(q))[0].pW + rng.normal(0, noise_mm, (n, 3))
    return PointSet(q, x, TOOL + [3.0, -2.0, 8.0], 0.0, np.zeros(3))


def test_the_model_adds_the_harmonics_to_the_joint_reading(ur5):
    """theta_i = q_i + offset + h1s sin q + h1c cos q + h2s sin 2q + h2c cos 2q, written out independently."""
    q = np.deg2rad(np.random.default_rng(0).uniform(-170, 170, (9, 6)))
    h = np.deg2rad(np.random.default_rng(1).normal(0, 0.5, (6, 4)))
    p = ModelParams.nominal(ur5, TOOL).with_(h=h)
    shift = sum(h[None, :, k] * f(order * q) for k, (order, f) in enumerate(HARMONICS.values()))
    moved = ModelParams.nominal(ur5, TOOL)
    expected = np.array([forward(moved.with_(theta_offset=moved.theta_offset + s), qq[None]).pW[0]
                         for qq, s in zip(q, shift)])
    assert np.abs(forward(p, q).pW - expected).max() < 1e-9
    with pytest.raises(ValueError, match="shape"):
        ModelParams.nominal(ur5, TOOL).with_(h=np.zeros((6, 2)))


def test_harmonic_jacobian_columns_match_finite_differences(ur5):
    """Every periodic column (centred on a reference, as identify sets it) against finite differences."""
    infos = catalogue(ur5.n, (), harmonics=(2, 4, 6))
    assert [i.name for i in infos][-12:-8] == ["h1s_2", "h1c_2", "h2s_2", "h2c_2"]
    rng = np.random.default_rng(5)
    q = rng.uniform(-3, 3, (11, 6))
    start = ModelParams.nominal(ur5, TOOL, base=np.array([5.0, 1.0, -3.0, 1.0, 2.0, 30.0]))
    start = start.with_(h_ref=harmonic_reference(q, (2, 4, 6)))
    x = rng.normal(0, 0.5, len(infos))
    p = apply(start, infos, x)
    fr = forward(p, q)
    J = position_jacobian(fr, np.zeros_like(q), infos, p.base)
    eps = 1e-6
    for k, info in enumerate(infos):
        if info.kind not in HARMONICS:
            continue
        x2 = x.copy()
        x2[k] += eps
        fd = (forward(apply(start, infos, x2), q).pW - fr.pW) / eps
        assert np.abs(J[:, :, k] - fd).max() < 1e-6 * max(1.0, np.abs(fd).max()), info.name
        assert np.abs(J[:, :, k]).max() > 1e-3, info.name                      # the column is not empty


def test_the_terms_are_centred_so_the_geometry_alone_stays_the_best_geometric_model(ur5):
    """A large once-per-turn error of joint 1 seen over 90 deg only: most of it is a constant over that range.
    The identified terms have no mean over the data, so the base takes the constant and the geometric model
    (all a URDF holds) misses only the ripple about that constant, not the terms' whole size."""
    truth = random_truth(ur5, TOOL, np.random.default_rng(3)).with_(base=np.array([800.0, -200.0, 50.0, 0.4, -0.3, 25.0]))
    truth = truth.with_(h=np.zeros((6, 4)) + np.deg2rad([[0.05, 0.3, 0.0, 0.0]] + [[0.0] * 4] * 5))
    rng = np.random.default_rng(16)
    q = rng.uniform(-170, 170, (250, 6))
    q[:, 0] = rng.uniform(-30, 60, 250)
    x = ball_positions(ur5, truth, np.deg2rad(q))[0].pW + rng.normal(0, 0.005, (250, 3))
    pts = PointSet(q, x, TOOL, 0.0, np.zeros(3))
    res = identify_points(ur5, pts, 0.005, fix_unidentifiable=True, harmonics=(1,))
    qr = np.deg2rad(q)
    dropped = np.linalg.norm(forward(res.params, qr).pW - forward(res.params.with_(h=np.zeros((6, 4))), qr).pW, axis=1)
    term_only = np.linalg.norm(forward(truth, qr).pW - forward(truth.with_(h=np.zeros((6, 4))), qr).pW, axis=1)
    assert dropped.mean() < 0.3 * term_only.mean(), (dropped.mean(), term_only.mean())
    assert res.harmonic_range_deg[1][0] == pytest.approx(q[:, 0].min()) and res.harmonic_range_deg[1][1] < 60.0
    assert any("joint 1's periodic error was identified over" in c for c in res.cautions)


def test_a_periodic_joint_error_is_recovered_and_improves_held_out_points(ur5):
    """Known truth: joint 4 turns q + 0.012 sin q - 0.009 cos q + ... deg. Identified with --joint-harmonics 4, the
    four terms come back within 4 sigma, the fit reaches the noise and the held-out error drops below the
    geometric model's."""
    truth = _truth(ur5)
    fit, test = _points(ur5, truth, 250, 10), _points(ur5, truth, 80, 11)
    plain = identify_points(ur5, fit, 0.005, fix_unidentifiable=True)
    res = identify_points(ur5, fit, 0.005, fix_unidentifiable=True, harmonics=(4,))
    got = np.array([res.values[f"{t}_4"] for t in HARMONICS])
    sig = np.array([res.sigma[f"{t}_4"] for t in HARMONICS])
    assert np.all(np.abs(got - H4_DEG) < 4 * sig), (got, sig)
    assert np.all(sig < 0.002)
    assert res.rms_mm < 0.0065 < plain.rms_mm
    assert validate(ur5, res.params, test)[0].mean_mm < 0.6 * validate(ur5, plain.params, test)[0].mean_mm


def test_a_robot_without_the_error_gets_harmonics_near_zero(ur5):
    """No periodic error in the truth: the identified terms are within 4 sigma of 0 (no invented structure)."""
    truth = _truth(ur5).with_(h=None)
    res = identify_points(ur5, _points(ur5, truth, 250, 12), 0.005, fix_unidentifiable=True, harmonics=(1, 4))
    for j in (1, 4):
        for t in HARMONICS:
            assert abs(res.values[f"{t}_{j}"]) < 4 * res.sigma[f"{t}_{j}"], (t, j)


def test_result_file_is_version_2_and_reads_back_to_the_same_model(ur5, tmp_path):
    truth = _truth(ur5)
    pts = _points(ur5, truth, 150, 13)
    res = identify_points(ur5, pts, None, fix_unidentifiable=True, harmonics=(4,))
    path = write_result(tmp_path / "h.cal.json", result_dict(ur5, res, "none"))
    assert json.loads(path.read_text())["format"] == "rodlab.calibration/2"
    back = calibrated_params(ur5, read_calibration(path))
    q = np.deg2rad(pts.q_deg[:20])
    assert np.abs(back.h - res.params.h).max() < 1e-12 and back.h[3].any()
    assert np.abs(forward(back, q).pW - forward(res.params, q).pW).max() < 1e-6
    plain = identify_points(ur5, pts, None, fix_unidentifiable=True)
    assert result_dict(ur5, plain, "none")["format"] == "rodlab.calibration/1"


def test_version_1_files_with_periodic_terms_are_refused_and_version_2_is_validated_and_reported(ur5, tmp_path):
    from rodlab.app.cli.main import main
    from rodlab.app.report import write_folder_report
    res = identify_points(ur5, _points(ur5, _truth(ur5), 150, 17), None, fix_unidentifiable=True, harmonics=(4,))
    good = write_result(tmp_path / "good.cal.json", result_dict(ur5, res, "none"))
    assert main(["validate", str(good)]) == 0
    data = json.loads(good.read_text())
    bad = tmp_path / "bad.cal.json"
    bad.write_text(json.dumps({**data, "format": "rodlab.calibration/1"}))
    with pytest.raises(CalibrationError, match="belong to \"rodlab.calibration/2\""):
        read_calibration(bad)
    del data["joint_harmonics"]
    bad.write_text(json.dumps(data))
    with pytest.raises(CalibrationError, match="no reference"):
        read_calibration(bad)
    bad.unlink()
    html = write_folder_report(tmp_path).read_text()
    assert "Calibration" in html and "h1s_4" in html and "identified over the readings joint 4:" in html


def test_unknown_joints_are_refused_with_the_valid_range(ur5):
    with pytest.raises(CalibrationError, match=r"joint numbers 1\.\.6"):
        identify_points(ur5, _points(ur5, _truth(ur5), 30, 14), None, harmonics=(7,))


def test_cli_export_and_errors(ur5, tmp_path, capsys):
    from rodlab.app.cli.main import main
    truth = _truth(ur5)
    pts = _points(ur5, truth, 150, 15)
    f = tmp_path / "p.validation.csv"
    rows = "\n".join(",".join(f"{v:.6f}" for v in [*q, *x]) for q, x in zip(pts.q_deg, pts.x_W_mm))
    f.write_text("# tool_mm: 18, 3, 128\nq1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm\n" + rows + "\n")
    cal = tmp_path / "c.json"
    assert main(["calibrate", "--points", str(f), "--robot", "ur5", "--fix-unidentifiable", "--noise-um", "5",
                 "--joint-harmonics", "4", "--json", str(cal)]) == 0
    assert "h1s_4" in capsys.readouterr().out
    out = tmp_path / "cal.urdf"
    assert main(["export", str(cal), "--urdf", str(ur5.path), "-o", str(out)]) == 0
    assert "periodic joint errors" in capsys.readouterr().out
    assert "Nor can the periodic joint errors" in out.read_text()
    assert "joint_harmonics:" in out.with_suffix(".yaml").read_text()
    for bad in ("1,x", " , ", "0"):                         # argparse refuses these before any work
        with pytest.raises(SystemExit) as e:
            main(["calibrate", "--points", str(f), "--robot", "ur5", "--joint-harmonics", bad])
        assert e.value.code == 2 and "expected joint numbers" in capsys.readouterr().err
    assert main(["calibrate", "--points", str(f), "--robot", "ur5", "--joint-harmonics", "9"]) == 2
    assert "1..6" in capsys.readouterr().err
    assert main(["calibrate", "--points", str(f), "--robot", "ur5", "--pin", "h1s_4=0"]) == 2
    assert "add joint 4 to --joint-harmonics" in capsys.readouterr().err
    assert main(["calibrate", "--sockets", str(f), "--robot", "ur5", "--joint-harmonics", "4"]) == 2
    assert "--sockets" in capsys.readouterr().err
    assert main(["diagnose", "--points", str(f), "--robot", "ur5", "--joint-harmonics", "4"]) == 0
    assert "periodic_joint_error (joint 4)" not in capsys.readouterr().out


def test_campaign_with_a_periodic_joint_error_is_calibrated(tx90, tmp_path, capsys):
    """A MultiCal campaign whose joint 4 turns q + 0.02 sin q (the campaign effect's own simulator), calibrated with
    --joint-harmonics 4: the error comes back as a /2 result (the diagnosis' skip of modelled joints is tested
    directly below)."""
    from rodlab import calc_rod_compliance, resolve_design
    from rodlab.app.cli.main import main
    from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
    rod = calc_rod_compliance(resolve_design("rod1"))
    simulate_campaign(tx90, rod, tmp_path, CampaignSpec(seed=23), effects={"periodic_joint_error": {"joint": 4,
                                                                                                    "amp_deg": 0.02}})
    rods = list(tmp_path.glob("*.compliance.json"))
    cal = tmp_path / "c.json"
    code = main(["calibrate", str(tmp_path / "multical.campaign.csv"), "--fixture", str(tmp_path / "multical.fixture.json"),
                 "--rod", str(rods[0]), "--joint-harmonics", "4", "--json", str(cal)])
    err = capsys.readouterr().err
    d = json.loads(cal.read_text())
    assert code in (0, 3) and d["format"] == "rodlab.calibration/2"
    h1s = d["parameters"]["h1s_4"]
    assert abs(h1s["value"] - 0.02) < max(4 * h1s["sigma"], 0.002), h1s
    assert "joint:4" not in err and "--joint-harmonics 4`" not in err


def test_joints_already_modelled_are_not_hypotheses_again(ur5):
    """The points candidates and the campaign effect's hypotheses leave out the joints the fit carries, and the
    points advice names the union of the joints."""
    from types import SimpleNamespace

    from rodlab.app.diagnose.points import point_candidates
    from rodlab.calibrate.effects.periodic_joint_error import PeriodicJointError
    q = np.deg2rad(np.random.default_rng(18).uniform(-170, 170, (40, 6)))
    fr = forward(ModelParams.nominal(ur5, TOOL), q)
    cols = np.random.default_rng(19).normal(size=(40, 6, 3))
    periodic = [c for c in point_candidates(q, cols, modelled=(4,)) if c[0] == "periodic_joint_error"]
    assert [c[1] for c in periodic] == ["joint 1", "joint 2", "joint 3", "joint 5", "joint 6"]
    assert "--joint-harmonics 1,4`" in periodic[0][3]
    ctx = SimpleNamespace(frames=fr, n_points=40, robot=ur5, obs=SimpleNamespace(q_rad=q),
                          result=SimpleNamespace(harmonic_range_deg={4: (-170.0, 170.0)}))
    where = [h.location for h in PeriodicJointError().hypotheses(ctx)]
    assert "joint:4" not in where and "joint:3" in where and len(set(where)) == 5
    assert len(where) == 10                             # once and twice per revolution at each joint


def test_an_initial_model_keeps_its_terms_and_refuses_to_drop_them(ur5):
    """identify(initial=...) re-centres the listed joints' terms on the new readings without changing the model,
    and refuses an initial model whose terms the call would drop."""
    from rodlab.calibrate.identify import harmonic_start
    truth = _truth(ur5)
    q_old, q_new = (np.deg2rad(np.random.default_rng(s).uniform(-170, 170, (50, 6))) for s in (20, 21))
    start = truth.with_(h_ref=harmonic_reference(q_old, (4,)))
    moved = harmonic_start(start, q_new, (4,))
    assert np.abs(moved.h_ref[3] - harmonic_reference(q_new, (4,))[3]).max() < 1e-12
    assert np.abs(forward(moved, q_new).pW - forward(start, q_new).pW).max() < 1e-9
    with pytest.raises(CalibrationError, match=r"joints \[4\] that would be dropped"):
        harmonic_start(start, q_new, ())


def test_a_fit_with_no_degree_of_freedom_is_not_trusted(ur5):
    """As many free parameters as readings: the residual test has nothing to judge, so the result is not trusted."""
    pts = _points(ur5, _truth(ur5), 9, 22)
    res = identify_points(ur5, pts, 0.005, fix_unidentifiable=True, harmonics=(1, 2, 3, 4, 5, 6))
    assert len(res.free) >= 27 and any("no degree of freedom" in w for w in res.warnings)


def test_version_2_readers_refuse_impossible_joints_names_and_ranges(ur5, tmp_path):
    res = identify_points(ur5, _points(ur5, _truth(ur5), 150, 23), None, fix_unidentifiable=True, harmonics=(4,))
    data = result_dict(ur5, res, "none")
    cases = [({**data, "parameters": {**data["parameters"], "h1s_x": {"value": 0.0, "unit": "deg"}}}, "named like"),
             ({**data, "joint_harmonics": {"4": {**data["joint_harmonics"]["4"], "q_min_deg": 50.0,
                                                 "q_max_deg": 10.0}}}, "above q_max_deg"),
             ({**data, "format": "rodlab.calibration/1", "parameters": {k: v for k, v in data["parameters"].items()
                                                                       if not k.startswith("h")}}, "belong to")]
    for i, (doc, match) in enumerate(cases):
        path = tmp_path / f"bad{i}.cal.json"
        path.write_text(json.dumps(doc))
        with pytest.raises(CalibrationError, match=match):
            read_calibration(path)
    seven = {**data, "joint_harmonics": {**data["joint_harmonics"], "7": data["joint_harmonics"]["4"]}}
    path = tmp_path / "seven.cal.json"
    path.write_text(json.dumps(seven))
    with pytest.raises(CalibrationError, match=r"joints \[7\]"):
        calibrated_params(ur5, read_calibration(path))
