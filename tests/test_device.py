"""The MultiCal device: device files, raw sensor readings through them, and the fixture fitted from probes.

Known truth: campaigns simulated with a device as built (sensors 2 and 3 off orthogonal by 2 deg) and the same
campaign (seed, robot, alignment, noise draws) with an orthogonal device; fixtures probed at the true poses."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab.app.cli.main import main
from rodlab.calibrate import (CalibrationError, campaign_observations, fit_fixture, identify, read_campaign,
                              read_device, read_fixture, read_points, read_probe, Rod, RodDeflection, validate,
                              write_device, write_fixture)
from rodlab.calibrate.device import ideal_device, misaligned_device
from rodlab.calibrate.observations import noise_covariance
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab.core.frames import pose_to_matrix


def _device(seed: int, deg: float = 2.0):
    return misaligned_device(ideal_device(), deg, np.random.default_rng([seed, 2]))


@pytest.fixture(scope="module")
def sims(tmp_path_factory, tx90, rod1_calc):
    """seed -> (folder of the as-built device's campaign, folder of the orthogonal device's same campaign)."""
    out = {}
    for seed in (1, 2, 3):
        root = tmp_path_factory.mktemp(f"raw{seed}")
        spec = CampaignSpec(seed=seed, alignment_mm=0.3)
        simulate_campaign(tx90, rod1_calc, root / "built", spec, device=_device(seed))
        simulate_campaign(tx90, rod1_calc, root / "ortho", spec, device=ideal_device())
        out[seed] = (root / "built", root / "ortho")
    return out


def _calibrate(robot, rod, folder, device, fixture="multical.fixture.json"):
    camp = read_campaign(folder / "multical.campaign.csv", robot.n, device)
    res = identify(robot, campaign_observations(camp, read_fixture(folder / fixture), rod), Rod.of(rod), [RodDeflection.of(rod)])
    return res, validate(robot, res.params, read_points(folder / "multical.validation.csv"))[0]


# ---------------------------------------------------------------- the device file


def test_device_round_trip_and_conversion(tmp_path):
    dev = _device(7)
    assert np.max(np.abs(dev.misalignment_deg())) == pytest.approx(2.0, abs=1e-9)
    back = read_device(write_device(dev, tmp_path / "d.device.json"))
    assert np.allclose(back.axes, dev.axes, atol=1e-12) and back.features_D_mm.keys() == dev.features_D_mm.keys()
    x = np.random.default_rng(0).normal(0, 0.2, (20, 3))
    assert np.allclose(back.positions(back.readings(x)), x, atol=1e-12)
    # flat tips on a sphere: sensor k moves by the axis component only
    assert np.allclose(back.readings(x) - back.zero_mm, x @ back.axes.T)
    # springs: the force at the datum is sum_k f0_k a_k; 1 mm further along sensor 1 the force falls by its rate
    F0 = back.force_D(back.zero_mm[None])[0]
    assert np.allclose(F0, np.array([1.10, 1.25, 1.05]) @ back.axes)
    s = back.zero_mm + [1.0, 0.0, 0.0]
    assert np.allclose(back.force_D(s[None])[0], F0 - 0.04 * back.axes[0])
    # orthogonal sensors: the noise of a point is the readings' (identity); misaligned, it grows along the skew
    assert np.allclose(ideal_device().noise_shape_D(), np.eye(3))
    assert np.trace(dev.noise_shape_D()) > 3.0


@pytest.mark.parametrize("edit, key", [
    (lambda d: d["sensors"][0].update(axis_D=[0.0, 1.0, 0.0]), "sensors[1].axis_D"),
    (lambda d: d["sensors"][1].update(axis_D=[0.0, 0.6, 0.8]), "sensors[2].axis_D"),
    (lambda d: d["sensors"][2].update(axis_D=[0.6, 0.8, 0.0]), "sensors"),
    (lambda d: d["sensors"][2].update(axis_D=[0.0, 0.0, 2.0]), "sensors[3].axis_D"),
    (lambda d: d["sensors"][1].update(axis_D=[0.0, -1.0, 0.0]), "sensors[2].axis_D"),     # sensor 2 reversed
    (lambda d: d["sensors"][2].update(axis_D=[0.0, 0.0, -1.0]), "sensors[3].axis_D"),     # sensor 3 reversed
    (lambda d: d["sensors"][1].update(zero_mm=40.0), "sensors[2].zero_mm"),
    (lambda d: d["sensors"][0].update(range_mm=[30.0, 0.0]), "sensors[1].range_mm"),
    (lambda d: d["sensors"][0].pop("zero_mm"), "sensors[1].zero_mm"),
    (lambda d: d["sensors"].pop(), "sensors"),
    (lambda d: d["sensors"][1].update(rate_N_per_mm=40.0), "sensors[2].rate_N_per_mm"),   # N/m written as N/mm
])
def test_device_file_refusals_name_the_key(tmp_path, edit, key):
    data = json.loads(write_device(ideal_device(), tmp_path / "d.device.json").read_text())
    edit(data)
    bad = tmp_path / "bad.device.json"
    bad.write_text(json.dumps(data, indent=1))
    with pytest.raises(CalibrationError) as e:
        read_device(bad)
    assert e.value.key == key and "bad.device.json" in str(e.value)
    assert main(["validate", str(bad)]) == 2


# ---------------------------------------------------------------- raw campaigns


def test_raw_campaign_calibrates_as_the_same_campaign_in_D(sims, tx90, rod1_calc):
    """The done-when: raw readings with the device file reach the validation accuracy of the same campaign
    given in {D} within 2 %; read as if the sensors were orthogonal, the 2 deg misalignment is visible in the fit:
    every fit NOT TRUSTED, its reduced chi-square at least twice the true device's."""
    for seed, (built, ortho) in sims.items():
        res_D, st_D = _calibrate(tx90, rod1_calc, ortho, ideal_device())
        res_raw, st_raw = _calibrate(tx90, rod1_calc, built, read_device(built / "multical.device.json"))
        res_bad, _ = _calibrate(tx90, rod1_calc, built, ideal_device())
        assert st_raw.mean_mm == pytest.approx(st_D.mean_mm, rel=0.02)
        assert not res_raw.warnings and not res_D.warnings
        assert res_bad.warnings
        assert res_bad.residual_check.reduced > 2.0 * res_raw.residual_check.reduced


def test_raw_conversion_noise_and_springs(sims, tx90, rod1_calc):
    built = sims[1][0]
    dev = read_device(built / "multical.device.json")
    camp = read_campaign(built / "multical.campaign.csv", 6, dev)
    fix = read_fixture(built / "multical.fixture.json")
    obs = campaign_observations(camp, fix, rod1_calc)
    # the contact force of each point is the springs' at its readings, turned to {W}
    j, i = int(camp.position[0]), 0
    R = pose_to_matrix(fix.poses[j])[:3, :3]
    assert np.allclose(obs.force_W_N[i], R @ dev.force_D(camp.readings_mm[i:i + 1])[0])
    assert np.ptp(np.linalg.norm(obs.force_W_N, axis=1)) > 1e-3        # not one constant force
    # the sensors' noise through the axes, in {W}: sigma^2 R A^-1 A^-T R^T per point, nothing across points
    S = noise_covariance(obs, 0.003, (0.0, 0.0))
    assert np.allclose(S[:3, :3], 0.003 ** 2 * R @ dev.noise_shape_D() @ R.T)
    assert not S[:3, 3:].any()


def test_pose_covariance_matching_the_default_gives_the_same_noise_model(sims, tx90, rod1_calc):
    folder = sims[1][1]
    camp = read_campaign(folder / "multical.campaign.csv", 6, ideal_device())
    fix = read_fixture(folder / "multical.fixture.json")
    S_default = noise_covariance(campaign_observations(camp, fix, rod1_calc), 0.003, (0.01, 0.002))
    fix.pose_cov = {j: np.diag([0.01] * 3 + [0.002] * 3) ** 2 for j in fix.poses}
    S_stated = noise_covariance(campaign_observations(camp, fix, rod1_calc), 0.003, (0.05, 0.05))
    assert np.allclose(S_default, S_stated, rtol=1e-12, atol=1e-18)


def _rewrite(path, line_no: int, col: str, value: str):
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    cells = lines[line_no - 1].split(",")
    cells[header.index(col)] = value
    lines[line_no - 1] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


def test_reading_outside_its_range_is_refused_with_its_place(sims, tmp_path, capsys):
    built = sims[2][0]
    camp = tmp_path / "c.campaign.csv"
    camp.write_text((built / "multical.campaign.csv").read_text())
    _rewrite(camp, 4, "s2_mm", "31.5")                                    # position 1, point 3
    with pytest.raises(CalibrationError) as e:
        read_campaign(camp, 6, read_device(built / "multical.device.json"))
    assert (e.value.line, e.value.key) == (4, "s2_mm")
    assert "position 1 point 3" in str(e.value) and "sensor 2" in str(e.value)
    args = ["calibrate", str(camp), "--fixture", str(built / "multical.fixture.json"), "--rod",
            str(built / "rod.compliance.json")]
    assert main(args + ["--device", str(built / "multical.device.json")]) == 2
    assert "position 1 point 3" in capsys.readouterr().err
    assert main(args) == 2                                              # raw readings without their device
    assert "--device" in capsys.readouterr().err


def test_far_point_warned_and_column_sets_checked(sims, tmp_path, capsys):
    built = sims[2][0]
    camp = tmp_path / "c.campaign.csv"
    camp.write_text((built / "multical.campaign.csv").read_text())
    _rewrite(camp, 3, "s1_mm", "15.9")                                  # position 1, point 2: ~0.9 mm out
    rc = main(["diagnose", "--campaign", str(camp), "--fixture", str(built / "multical.fixture.json"), "--rod",
               str(built / "rod.compliance.json"), "--device", str(built / "multical.device.json")])
    err = capsys.readouterr().err
    assert rc in (0, 3) and "farther than 0.5 mm" in err and "position 1 point 2 (line 3)" in err
    assert main(["validate", str(camp)]) == 0
    both = tmp_path / "both.campaign.csv"
    lines = camp.read_text().splitlines()
    both.write_text("\n".join([lines[0] + ",x_mm"] + [ln + ",0" for ln in lines[1:]]) + "\n")
    with pytest.raises(CalibrationError, match="not both"):
        read_campaign(both)
    assert main(["validate", str(both)]) == 2
    xyz = sims[2][0].parent / "xyz.campaign.csv"
    xyz.write_text(camp.read_text().replace("s1_mm,s2_mm,s3_mm", "x_mm,y_mm,z_mm"))
    with pytest.raises(CalibrationError, match="leave --device out"):
        read_campaign(xyz, 6, ideal_device())


def test_simulate_campaign_raw_cli(tmp_path, rod1_calc, capsys):
    from rodlab.core.compliance import write_compliance
    rod = write_compliance(rod1_calc, tmp_path / "rod.compliance.json")
    assert main(["simulate-campaign", "--rod", str(rod), "--raw", "--misalign-deg", "2", "--positions", "3",
                 "--orientations", "4", "-o", str(tmp_path / "c")]) == 0
    dev = read_device(tmp_path / "c" / "multical.device.json")
    assert np.max(np.abs(dev.misalignment_deg())) == pytest.approx(2.0, abs=1e-6)
    assert read_campaign(tmp_path / "c" / "multical.campaign.csv").raw
    files = [str(tmp_path / "c" / f) for f in ("multical.device.json", "nominal.device.json", "multical.probe.csv",
                                               "multical.campaign.csv")]
    assert main(["validate", *files]) == 0


# ---------------------------------------------------------------- the fixture from probing


def _mahalanobis(d, C):
    d = np.asarray(d, float).copy()
    d[3:] = (d[3:] + 180) % 360 - 180
    return float(d @ np.linalg.solve(C, d))


def test_fixture_from_probes_reproduces_the_true_poses(sims, tx90, rod1_calc, tmp_path):
    """Poses within their fitted uncertainty of the truth; the calibration with the probed fixture is the one
    with the true poses (within 5 %, probes of 2 um) and on average no worse than with the simulator's recorded
    fixture (poses noisy by 10 um / 2 mdeg; probes of 5 um: about 15 um / 7 mdeg, one seed's fit may be 12 %
    worse, another's better)."""
    from scipy.stats import chi2

    from rodlab.calibrate import Fixture
    from rodlab.calibrate.probe import simulated_probe_text
    all_d2, p5, rec = [], [], []
    for seed, (built, _) in sims.items():
        truth = json.loads((built / "truth.json").read_text())
        recorded = read_fixture(built / "multical.fixture.json")
        dev = read_device(built / "multical.device.json")
        fit5 = fit_fixture(read_probe(built / "multical.probe.csv"), dev, recorded.world_position)
        assert not fit5.flagged
        d2 = [_mahalanobis(fit5.fixture.poses[j] - np.array(truth["true_fixture_poses_W"][str(j)]),
                           fit5.fixture.pose_cov[j]) for j in fit5.fixture.pose_cov]
        assert max(d2) < chi2.ppf(0.999, 6) and len(d2) == 4
        all_d2 += d2
        true_T = {int(j): pose_to_matrix(p) for j, p in truth["true_fixture_poses_W"].items()}
        fine = tmp_path / f"fine{seed}.probe.csv"
        fine.write_text(simulated_probe_text(true_T, dev, 0.002, np.random.default_rng(seed)))
        fit2 = fit_fixture(read_probe(fine), dev, recorded.world_position)
        exact = Fixture({int(j): np.array(p) for j, p in truth["true_fixture_poses_W"].items()}, recorded.force_D_N,
                        recorded.world_position)
        stats = {}
        for name, fx in (("probed2", fit2.fixture), ("probed5", fit5.fixture), ("exact", exact),
                         ("recorded", recorded)):
            path = write_fixture(fx, built / f"{name}.fixture.json")
            back = read_fixture(path)
            if fx.pose_cov:
                assert json.loads(path.read_text())["format"] == "rodlab.fixture/2"
                assert all(np.allclose(back.pose_cov[j], fx.pose_cov[j], rtol=1e-5) for j in fx.pose_cov)
            res, stats[name] = _calibrate(tx90, rod1_calc, built, dev, path.name)
            assert not res.warnings and res.residual_check.poses_stated == bool(fx.pose_cov)
        assert stats["probed2"].mean_mm == pytest.approx(stats["exact"].mean_mm, rel=0.05)
        p5.append(stats["probed5"].mean_mm)
        rec.append(stats["recorded"].mean_mm)
    assert np.mean(p5) <= 1.1 * np.mean(rec)
    assert 1.0 < np.mean(all_d2) < 15.0           # chi-square(6) has mean 6: the stated uncertainty is the real one


def test_misprobed_feature_is_flagged(sims, tmp_path, capsys):
    built = sims[3][0]
    probe = tmp_path / "p.probe.csv"
    lines = (built / "multical.probe.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("2,ball_2,"))
    k1 = next(i for i, ln in enumerate(lines) if ln.startswith("2,ball_1,"))
    b2, b1 = (np.array([float(v) for v in lines[i].split(",")[2:]]) for i in (k, k1))
    moved = b2 + 0.05 * (b2 - b1) / np.linalg.norm(b2 - b1)          # 50 um off (accuracy 5 um), away from ball_1
    lines[k] = "2,ball_2," + ",".join(f"{v:.4f}" for v in moved)
    probe.write_text("\n".join(lines) + "\n")
    out = tmp_path / "f.fixture.json"
    rc = main(["fixture", str(probe), "--device", str(built / "multical.device.json"), "--world-position", "3",
               "-o", str(out)])
    err = capsys.readouterr().err
    assert rc == 3 and "FLAGGED position 2" in err and "'ball_2'" in err
    assert json.loads(out.read_text())["probing"]["flagged"].keys() == {"2"}
    assert main(["validate", str(out), str(probe)]) == 0
    rc = main(["calibrate", str(built / "multical.campaign.csv"), "--fixture", str(out), "--rod",
               str(built / "rod.compliance.json"), "--device", str(built / "multical.device.json")])
    assert rc in (0, 3) and "its probing flagged position 2: ball_2" in capsys.readouterr().err


@pytest.mark.parametrize("edit, line, key, words", [
    (lambda ls: ls.__setitem__(3, ls[3].replace("ball_1", "bal_1")), 4, "feature", "Did you mean `ball_1`"),
    (lambda ls: ls.__setitem__(2, ls[2].replace(",pin,", ",stud,")), 3, "feature", "not in the"),
    (lambda ls: ls.__setitem__(4, ls[4].rsplit(",", 1)[0] + ",abc"), 5, "z_mm", "expected a number"),
    (lambda ls: ls.__setitem__(4, ls[3]), 5, "feature", "appears twice"),
    (lambda ls: ls.__setitem__(0, "# instrument: arm"), 1, "accuracy_mm", "accuracy"),
    (lambda ls: [ls.pop(3), ls.pop(3)], 3, "feature", "at least 3 features"),
])
def test_bad_probe_files_are_refused_with_their_place(sims, tmp_path, edit, line, key, words):
    built = sims[1][0]
    lines = (built / "multical.probe.csv").read_text().splitlines()
    edit(lines)
    probe = tmp_path / "bad.probe.csv"
    probe.write_text("\n".join(lines) + "\n")
    with pytest.raises(CalibrationError) as e:
        fit_fixture(read_probe(probe), read_device(built / "multical.device.json"), 3)
    assert (e.value.line, e.value.key) == (line, key) and words in str(e.value)
    assert main(["fixture", str(probe), "--device", str(built / "multical.device.json"), "--world-position", "3",
                 "-o", str(tmp_path / "never.fixture.json")]) == 2
    assert not (tmp_path / "never.fixture.json").exists()


def test_world_position_must_be_probed_and_covariances_checked(sims, tmp_path):
    built = sims[1][0]
    bare = read_device(built / "multical.device.json")
    bare.features_D_mm = {}
    with pytest.raises(CalibrationError) as e:
        fit_fixture(read_probe(built / "multical.probe.csv"), bare, 3)
    assert e.value.key == "features_D_mm"
    with pytest.raises(CalibrationError, match="was not probed"):
        fit_fixture(read_probe(built / "multical.probe.csv"), read_device(built / "multical.device.json"), 9)
    fit = fit_fixture(read_probe(built / "multical.probe.csv"), read_device(built / "multical.device.json"), 3)
    data = json.loads(write_fixture(fit.fixture, tmp_path / "f.fixture.json").read_text())
    data["pose_covariance"]["1"][0][1] += 1.0
    bad = tmp_path / "bad.fixture.json"
    bad.write_text(json.dumps(data))
    with pytest.raises(CalibrationError) as e:
        read_fixture(bad)
    assert e.value.key == "pose_covariance.1" and "symmetric" in str(e.value)


def test_cli_names_an_orthogonal_design_when_the_fit_is_not_trusted(sims, tmp_path, capsys):
    built = sims[1][0]
    nominal = write_device(ideal_device(), tmp_path / "nominal.device.json")
    args = ["calibrate", str(built / "multical.campaign.csv"), "--fixture", str(built / "multical.fixture.json"),
            "--rod", str(built / "rod.compliance.json")]
    assert main(args + ["--device", str(nominal)]) == 3
    assert "states exactly orthogonal sensors" in capsys.readouterr().err
    assert main(args + ["--device", str(built / "multical.device.json")]) == 0


def test_a_flagged_fixture_heads_the_reasons_not_to_trust(sims, tmp_path, capsys):
    """A probe file with a decimal point slipped (the new-user trial's 389.4049 -> 38.94049): `rodlab fixture`
    flags the position, and the calibration with that fixture names the flagged probing first, not the innocent
    positions the residuals point at."""
    built = sims[3][0]
    probe = tmp_path / "p.probe.csv"
    lines = (built / "multical.probe.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("1,ball_2,"))
    cells = lines[k].split(",")
    cells[2] = f"{float(cells[2]) / 10:.5f}"
    lines[k] = ",".join(cells)
    probe.write_text("\n".join(lines) + "\n")
    fixture = tmp_path / "f.fixture.json"
    assert main(["fixture", str(probe), "--device", str(built / "multical.device.json"), "--world-position", "3",
                 "-o", str(fixture)]) == 3
    capsys.readouterr()
    rc = main(["calibrate", str(built / "multical.campaign.csv"), "--fixture", str(fixture), "--rod",
               str(built / "rod.compliance.json"), "--device", str(built / "multical.device.json")])
    err = capsys.readouterr().err
    assert rc == 3
    reasons = err.split("NOT TRUSTED - do not load these parameters into the robot:", 1)[1].lstrip()
    assert reasons.startswith(f"- the fixture file {fixture} was written with its probing flagged (position 1:")
