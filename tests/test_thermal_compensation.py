"""Thermal growth of the rod as a compensation through the calibrator's seam: a steel rod warming 5 K during a
campaign moves the ball by tens of um; compensated from the temp_C column and the parts' CTE, the residuals
return to the device noise and the identified robot to what a campaign at constant temperature gives."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import calc_rod_compliance, resolve_design
from rodlab.calibrate import (campaign_observations, identify, read_campaign, read_fixture, read_points,
                              resolve_robot, Rod, RodDeflection, ThermalGrowth, validate)
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab.core.materials import get_material

DESIGN = resolve_design("rod4")


def test_growth_is_each_members_cte_times_its_span():
    """A rod made of one material grows along its tool vector by CTE x tool (a homogeneous body scales)."""
    from dataclasses import replace
    g = ThermalGrowth.of_design(DESIGN).growth_T_mm_per_K
    assert np.all(np.isfinite(g)) and np.linalg.norm(g) > 1e-3            # steel, ~0.5 m: several um/K
    assert g @ DESIGN.tool_mm > 0                                          # it grows, outwards
    # the tubes carry most of it: with carbon tubes (CTE ~ -0.4 ppm/K) the growth nearly vanishes
    cfrp = get_material("cfrp")
    carbon = replace(DESIGN, pipe_I=replace(DESIGN.pipe_I, material=cfrp), pipe_II=replace(DESIGN.pipe_II, material=cfrp))
    assert np.linalg.norm(ThermalGrowth.of_design(carbon).growth_T_mm_per_K) < 0.3 * np.linalg.norm(g)


def test_offsets_follow_the_flange_and_vanish_at_the_reference_temperature():
    robot = resolve_robot("tx90")
    from rodlab.calibrate import ModelParams
    from rodlab.calibrate.compensations import Poses
    p = ModelParams.nominal(robot, DESIGN.tool_mm)
    th = ThermalGrowth(np.array([0.0, 0.0, 0.01]), T_ref_C=20.0)
    q = np.deg2rad([[0, 10, 90, 0, 30, 0], [40, -20, 100, 30, -40, 60]])
    off = th.offsets(robot, p, Poses(q, temp_C=[20.0, 25.0]))
    assert np.allclose(off[0], 0.0)
    assert np.linalg.norm(off[1]) == pytest.approx(0.05, rel=1e-12)       # 5 K x 10 um/K, rotated with {T}


def _campaign(out, temp_K_per_s):
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(DESIGN)
    th = ThermalGrowth.of_design(DESIGN)
    simulate_campaign(robot, rod, out, CampaignSpec(seed=5), compensations=[th], temp_K_per_s=temp_K_per_s)
    return robot, rod, th, out


@pytest.fixture(scope="module")
def warm_campaign(tmp_path_factory):
    return _campaign(tmp_path_factory.mktemp("warm"), 2e-3)          # ~5 K warmer at the end


def _identify(robot, rod, out, extra=()):
    camp = read_campaign(out / "multical.campaign.csv", robot.n)
    obs = campaign_observations(camp, read_fixture(out / "multical.fixture.json"), rod)
    res = identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod), *extra])
    val = validate(robot, res.params, read_points(out / "multical.validation.csv", robot.n))[1]
    return camp, res, float(np.mean(val))


def test_thermal_compensation_gives_what_a_constant_temperature_gives(warm_campaign, tmp_path):
    """The same campaign (seed) at constant temperature is the reference: compensated, the warming campaign
    identifies the same robot (validation mean within 0.5 um, residual rms within 0.1 um); uncompensated, the
    residual test finds physics missing and the rms grows by half."""
    robot, rod, th, out = warm_campaign
    camp, plain, v_plain = _identify(robot, rod, out)
    assert np.ptp(camp.temp_C) > 3.0                                       # the room warmed during the campaign
    _, comp, v_comp = _identify(robot, rod, out, (th,))
    _, ref, v_ref = _identify(*_campaign(tmp_path, 0.0)[:2], tmp_path)
    rms = lambda r: float(np.sqrt(np.mean(r.residuals_mm ** 2)))          # noqa: E731
    assert plain.residual_check.missing and not comp.residual_check.missing
    assert rms(plain) > 1.3 * rms(comp)
    assert rms(comp) == pytest.approx(rms(ref), abs=1e-4)
    assert v_comp == pytest.approx(v_ref, abs=5e-4) and v_plain > v_comp


def test_cli_thermal_needs_temperatures(tmp_path, warm_campaign, capsys):
    from rodlab.app.cli.main import main
    robot, rod, th, out = warm_campaign
    args = ["calibrate", str(out / "multical.campaign.csv"), "--fixture", str(out / "multical.fixture.json"),
            "--rod", str(out / "rod.compliance.json"), "--thermal", "rod4", "--json", str(tmp_path / "cal.json")]
    assert main(args) in (0, 3)
    import json
    assert json.loads((tmp_path / "cal.json").read_text())["compensation"].endswith("+thermal")
    lines = (out / "multical.campaign.csv").read_text().splitlines()
    cut = tmp_path / "no_temp.campaign.csv"
    cut.write_text("\n".join(",".join(l.split(",")[:-1]) for l in lines) + "\n")
    args[1] = str(cut)
    args[-1] = str(tmp_path / "bad.json")
    assert main(args) == 2
    assert "temp_C" in capsys.readouterr().err and not (tmp_path / "bad.json").exists()
