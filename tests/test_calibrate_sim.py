"""Synthetic campaigns (the project's own generator) and observability-based planning."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab.calibrate import (campaign_observations, identify, ModelParams, read_campaign, read_fixture, read_points,
                              resolve_robot, Rod, RodDeflection, validate)
from rodlab.calibrate.plan import observability, plan_poses
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab import calc_rod_compliance, resolve_design


@pytest.fixture(scope="module")
def robot():
    return resolve_robot("tx90")


@pytest.fixture(scope="module")
def rod():
    return calc_rod_compliance(resolve_design("rod1"))


def test_simulated_campaign_round_trip(tmp_path_factory, robot, rod):
    out = tmp_path_factory.mktemp("camp")
    truth = simulate_campaign(robot, rod, out, CampaignSpec(seed=11))
    camp = read_campaign(out / "multical.campaign.csv")
    fix = read_fixture(out / "multical.fixture.json")
    pts = read_points(out / "multical.validation.csv")
    assert camp.n == 30 and set(fix.poses) == {1, 2, 3, 4, 5}
    assert np.abs(camp.x_D_mm).max() < 1.0                 # aligned with the datum points (deflection included)
    res = identify(robot, campaign_observations(camp, fix, rod), Rod.of(rod), [RodDeflection.of(rod)])
    assert res.rms_mm < 0.01
    after = validate(robot, res.params, pts)[0]
    before = validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)[0]
    assert after.mean_mm < 0.1 < before.mean_mm
    assert res.values["tool_x"] == pytest.approx(rod.tool_mm[0] + truth["a_mm"][5] - robot.a_mm[5], abs=0.05)
    json.loads((out / "truth.json").read_text())


def test_planning_beats_a_random_choice(robot, rod, examples):
    fix = read_fixture(examples / "campaign-null" / "multical.fixture.json")
    poses, obs = plan_poses(robot, fix, Rod.of(rod), k=6, candidates=10, seed=2)
    assert all(v.shape == (6, 6) for v in poses.values())
    lim = robot.limits_deg
    for q in poses.values():
        assert np.all(q >= lim[:, 0] - 1e-6) and np.all(q <= lim[:, 1] + 1e-6)
    assert obs["parameters"] == 32 and obs["O1"] > 0
    assert set(obs) >= {"O1", "O2", "O3", "O4", "O5"}
    rng = np.random.default_rng(0)
    J = rng.normal(size=(90, 32))
    assert observability(J)["O2"] == pytest.approx(1 / observability(J)["condition"])


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_clean_campaign_is_trusted_and_compliances_stay_physical(tmp_path, capsys, seed):
    """A campaign with no effect, calibrated with its own compliance file, passes the trust checks (exit 0):
    joint compliances are bounded to [0, C_MAX] by construction, so a weakly identified wrist compliance can
    no longer come out negative and raise a false NOT TRUSTED (seed 1 did, c_6 = -3.6 +- 10.8 urad/(N m))."""
    from rodlab.calibrate.estimate import C_MAX
    from rodlab.app.cli import main
    from rodlab.core.compliance import write_compliance
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(resolve_design("rod1"))
    write_compliance(rod, tmp_path / "rod.json")
    assert main(["simulate-campaign", "--rod", str(tmp_path / "rod.json"), "--seed", str(seed), "-o",
                 str(tmp_path)]) == 0
    code = main(["calibrate", str(tmp_path / "multical.campaign.csv"), "--fixture",
                 str(tmp_path / "multical.fixture.json"), "--rod", str(tmp_path / "rod.compliance.json"),
                 "--validate", str(tmp_path / "multical.validation.csv"), "--json", str(tmp_path / "cal.json")])
    out = capsys.readouterr().out
    assert code == 0 and "NOT TRUSTED" not in out, out
    cal = json.loads((tmp_path / "cal.json").read_text())
    assert cal["trusted"] is True
    values = [p["value"] for k, p in cal["parameters"].items() if k.startswith("c_")]
    assert len(values) == robot.n and all(0.0 <= v <= C_MAX for v in values), values
    truth = json.loads((tmp_path / "truth.json").read_text())
    assert len(truth["c_rad_per_Nm"]) == robot.n
