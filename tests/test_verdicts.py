"""One story between `rodlab calibrate` and `rodlab diagnose --campaign`: one residual test, the suspects and
what to do about them, and the uncompensated rod named by both."""
from __future__ import annotations

import numpy as np

from rodlab import read_compliance
from rodlab.calibrate import (campaign_observations, identify, read_campaign, read_fixture, resolve_robot, Rod,
                              RodDeflection)
from rodlab.core.compliance import RodCompliance, write_compliance


def _obs(ex, rod):
    return campaign_observations(read_campaign(ex / "multical.campaign.csv"), read_fixture(ex / "multical.fixture.json"),
                                 rod)


def test_residual_test_is_chi_square_under_the_noise_model(examples):
    """Pure noise of the stated model passes the test at the rate its p-value says; the campaign with a
    displaced clamping position fails it by orders of magnitude."""
    from rodlab.calibrate.identify import noise_covariance
    from rodlab.calibrate.residual_test import P_MISSING, whitened_projection
    robot = resolve_robot("tx90")
    ex = examples / "campaign-null"
    rod = read_compliance(ex / "rod1.compliance.json")
    obs = _obs(ex, rod)
    res = identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod)])
    assert res.residual_check is not None and not res.residual_check.missing
    assert 0.5 < res.residual_check.reduced < 2.0
    # residuals drawn from the noise model itself: the whitened, projected sum of squares is chi-square(dof)
    from rodlab.calibrate.jacobian import position_jacobian
    from rodlab.calibrate.kinematics import ball_positions
    fr, tau = ball_positions(robot, res.params, obs.q_rad, obs.rod, force_W_N=obs.force_W_N)
    J = position_jacobian(fr, tau, [i for i in res.infos if i.name in res.free], res.params.base,
                          obs.group).reshape(res.residuals_mm.size, -1)
    S = noise_covariance(obs, 0.003)
    rng = np.random.default_rng(0)
    Lc = np.linalg.cholesky(S)
    chi = [float(np.sum(whitened_projection(Lc @ rng.standard_normal(S.shape[0]), J, Lc) ** 2)) for _ in range(200)]
    dof = S.shape[0] - J.shape[1]
    assert abs(np.mean(chi) / dof - 1.0) < 0.05
    bad = examples / "campaign-fixture_pose"
    rod = read_compliance(bad / "rod1.compliance.json")
    r2 = identify(robot, _obs(bad, rod), Rod.of(rod), [RodDeflection.of(rod)])
    assert r2.residual_check.missing and r2.residual_check.p_value < P_MISSING * 1e-20
    assert any("reduced chi-square" in w and "diagnose" in w for w in r2.warnings)


def test_untrusted_calibration_names_the_suspect_and_the_fix(examples, capsys):
    """The displaced clamping position: calibrate exits 3, names fixture_pose at position 1 and the options
    that identify it; re-run with them, the result is trusted."""
    from rodlab.app.cli import main
    ex = examples / "campaign-fixture_pose"
    args = ["calibrate", str(ex / "multical.campaign.csv"), "--fixture", str(ex / "multical.fixture.json"),
            "--rod", str(ex / "rod1.compliance.json")]
    assert main(args) == 3
    err = capsys.readouterr().err
    assert "fixture_pose at position:1" in err
    frees = "--free fixture_1_x --free fixture_1_y --free fixture_1_z"
    assert frees in err
    assert main(args + frees.split()) == 0


def test_uncompensated_rod_is_one_story(examples, tmp_path, capsys):
    """No compensation on a clean campaign: calibrate is trusted (its residuals pass the noise model) and
    notes the rod's uncompensated deflection; diagnose, given the method-none file, names rod_deflection
    (the file's matrices are zero), never `consistent`, and its compensation improves the validation."""
    from rodlab.app.cli import main
    from rodlab.app.diagnose import diagnose_campaign
    from rodlab.calibrate import read_points
    ex = examples / "campaign-null"
    rod = read_compliance(ex / "rod1.compliance.json")
    assert main(["calibrate", str(ex / "multical.campaign.csv"), "--fixture", str(ex / "multical.fixture.json"),
                 "--rod", str(ex / "rod1.compliance.json"), "--compensation", "none"]) == 0
    assert "not compensated" in capsys.readouterr().out
    none = write_compliance(RodCompliance.none_like(rod), tmp_path / "none.compliance.json")
    diag, info = diagnose_campaign(resolve_robot("tx90"), read_campaign(ex / "multical.campaign.csv"),
                                   read_fixture(ex / "multical.fixture.json"), read_compliance(none),
                                   validate_points=read_points(ex / "multical.validation.csv"))
    assert diag.verdict == "explained"
    assert (diag.findings[0].effect, diag.findings[0].location) == ("rod_deflection", None)  # contract: null
    assert {"k_gravity", "k_force"} <= set(diag.findings[0].parameters)
    v = diag.extra["validation"]
    assert v["after"]["mean_mm"] < v["before"]["mean_mm"]


def test_every_campaign_effect_has_a_remedy():
    from rodlab.app.diagnose.advice import remedy
    from rodlab.app.diagnose.report import Finding
    for eff, loc, params in (("fixture_pose", "position:2", {}), ("rod_deflection", None, {"k": 1.3}),
                             ("rod_deflection", None, {"k_gravity": 1.0, "k_force": 1.0}),
                             ("rod_deflection", None, {"k": 0.01}), ("outliers", "points:3,7", {}),
                             ("periodic_joint_error", "joint:2", {}), ("thermal_drift", "time", {}),
                             ("unexplained", "position:4", {})):
        text = remedy(Finding(eff, loc, "", params, {}, 0.0, 0.0))
        assert "docs/diagnose.md" not in text and len(text) > 40, (eff, text)
    assert "--free fixture_2_x" in remedy(Finding("fixture_pose", "position:2", "", {}, {}, 0.0, 0.0))


def test_a_deflection_left_uncompensated_on_purpose_is_not_blamed_on_the_file(tmp_path, capsys):
    """The soft steel rod 5# calibrated with --compensation none: NOT TRUSTED, and the suspect says the calibration
    did not compensate the deflection, not that the (right) compliance file is another rod's (a trial: "0.208x ...
    what the compliance file says (a file of another rod ...)")."""
    from rodlab.app.cli import main
    out = tmp_path / "c"
    assert main(["simulate-campaign", "--rod", "rod5", "--seed", "4", "-o", str(out)]) == 0
    capsys.readouterr()
    assert main(["calibrate", str(out / "multical.campaign.csv"), "--fixture", str(out / "multical.fixture.json"),
                 "--rod", str(out / "rod.compliance.json"), "--compensation", "none"]) == 3
    err = capsys.readouterr().err
    said = next(line for line in err.splitlines() if line.startswith("  - rod_deflection"))
    assert "this calibration does not compensate it (--compensation none)" in said
    assert "another rod" not in said and "what the compliance file says" not in said
