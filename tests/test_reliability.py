"""Untrustworthy results are refused or flagged; extreme designs succeed with an error estimate or are refused."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.calibrate import (campaign_observations, identify, read_campaign, read_fixture, resolve_robot, Rod,
                              RodDeflection)
from rodlab.fea import FeaError
from rodlab.fea.compute import estimated_dofs, solid_compliance
from rodlab import read_compliance
from rodlab.core.design_io import design_from_dict


def test_untrusted_calibration_is_flagged(examples):
    robot = resolve_robot("tx90")
    for name, trusted in (("campaign-null", True), ("campaign-fixture_pose", False)):
        ex = examples / name
        rod = read_compliance(ex / "rod1.compliance.json")
        res = identify(robot, campaign_observations(read_campaign(ex / "multical.campaign.csv"),
                                                    read_fixture(ex / "multical.fixture.json"), rod),
                       Rod.of(rod), [RodDeflection.of(rod)])
        assert (not res.warnings) == trusted, res.warnings
        if not trusted:
            assert any("diagnose" in w for w in res.warnings)


def test_cli_refuses_untrusted(examples, tmp_path, capsys):
    from rodlab.app.cli import main
    ex = examples / "campaign-fixture_pose"
    rc = main(["calibrate", str(ex / "multical.campaign.csv"), "--fixture", str(ex / "multical.fixture.json"),
               "--rod", str(ex / "rod1.compliance.json"), "--json", str(tmp_path / "c.json")])
    assert rc == 3 and "NOT TRUSTED" in capsys.readouterr().err
    import json
    assert json.loads((tmp_path / "c.json").read_text())["trusted"] is False


def _design(**over):
    data = {"format": "rodlab.rod/1", "name": "x", "L1_mm": 300.0, "L2_mm": 450.0, "gamma_deg": 90.0,
            "tube": {"material": "steel_304", "outer_diameter_mm": 20.0, "wall_mm": 2.0}}
    data.update(over)
    return design_from_dict(data)


def test_thin_walls_are_refused_with_the_reason():
    d = _design(tube={"material": "cfrp", "outer_diameter_mm": 25.0, "wall_mm": 0.3})
    assert estimated_dofs(d, 0.9) > 1.5e6
    with pytest.raises(FeaError, match="M DOFs .* --size .* --model frame"):
        solid_compliance(d, mesher=lambda *a, **k: pytest.fail("must refuse before meshing"))


@pytest.mark.cad
@pytest.mark.parametrize("gamma", [45.0, 179.0])
def test_extreme_bends_solve_with_an_error_estimate(gamma):
    pytest.importorskip("gmsh")
    from rodlab.geometry import mesh_rod
    d = _design(gamma_deg=gamma, L1_mm=400.0, L2_mm=400.0, bend={"radius_mm": 30.0})
    comp, res = solid_compliance(d, mesh_rod, size_mm=8.0,
                                 error_estimate=True)
    err = comp.provenance["discretisation_error"]
    assert np.all(np.isfinite(comp.C_F)) and 0 < err["max_relative_C_F"] < 0.05
    assert res.symmetry_defect < 1e-6
