"""A tilted load line (crosstalk's load form): the rod carries a side force during the holds of one load
direction. An independent simulator's tilted loads had been named a non-linearity (exact simulation) or missed
(the design's envelope); a tilted gauge and a tilted load differ where a gauge is read under two load axes."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import calc_rod_compliance
from conftest import legacy_design
from rodlab.app.diagnose import diagnose_rig
from rodlab.core.enums import LoadAxis, Phase
from rodlab.stiffness_rig import RigError, read_recording
from rodlab.stiffness_rig.effects import RigEffect, joint_places
from rodlab.core.units import G0
from rodlab.stiffness_rig.model import Hold, LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

DESIGN = legacy_design("rod1")
SIM = calc_rod_compliance(DESIGN)


def test_a_tilted_load_line_carries_a_side_force_in_its_own_series_only():
    """Force along the line: |F| (cos eps e_axis + sin eps e_side) for the tilted direction, untouched for the
    others; the load cell in the line reads |F|; the gauges read C_F times that force."""
    eps = 0.04
    model = RigModel(SIM.C_F, {"crosstalk": {"load": "-z", "eps_x_rad": eps}}, noise_mm=0.0, resolution_mm=0.0,
                     load_cell_noise_N=0.0)
    assert "sensor" not in model.effects[RigEffect.CROSSTALK]
    m = 1.5
    tilted = Hold(1, LoadAxis.NEG_Z, 1, Phase.LOAD, m, 0.0)
    F = model.force_on_rod(tilted)
    np.testing.assert_allclose(F, m * G0 * np.array([np.sin(eps), 0.0, -np.cos(eps)]), rtol=1e-12)
    assert model.load_cell(tilted) == pytest.approx(m * G0, abs=1e-3)
    np.testing.assert_allclose(model.reading(0.0, tilted)[0], SIM.C_F @ F, rtol=1e-12)
    straight = Hold(2, LoadAxis.Z, 1, Phase.LOAD, m, 0.0)
    np.testing.assert_allclose(model.force_on_rod(straight), [0.0, 0.0, m * G0], rtol=1e-12)


@pytest.mark.parametrize("spec, message", [
    ({"crosstalk": {"load": "x", "eps_x_rad": 0.01}}, "other than its own"),
    ({"crosstalk": {"load": "y", "sensor": "z", "eps_x_rad": 0.01}}, "not both"),
    ({"crosstalk": {"load": "w", "eps_x_rad": 0.01}}, "must be one of"),
])
def test_bad_load_tilts_are_refused_with_the_key(spec, message):
    with pytest.raises(RigError, match=message):
        RigModel(SIM.C_F, spec)


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_a_tilted_load_is_named_crosstalk_of_that_load_not_of_a_gauge(tmp_path, accuracy):
    """The x load leaning 0.03 rad towards z (its z gauge reads C33 x sin(eps) x |F|): named crosstalk at
    ``load:x`` with eps within 5 % against an exact simulation. Against the design's envelope the free linear
    compliance (c13 = c31) takes the symmetric part, and what is left is the same for a load x leaning towards z
    and an x gauge tilted towards z: the location names both, and how to tell them apart."""
    eps = 0.03
    model = RigModel(SIM.C_F, {"crosstalk": {"load": "x", "eps_z_rad": eps}}, noise_mm=0.0006, resolution_mm=0.0001,
                     seed=5, places=joint_places(DESIGN.tool_mm, DESIGN))
    path = simulate_recording(model, LoadSchedule(repeats=3, hold_s=6.0), tmp_path / "tilt.rig.csv", rod=DESIGN.name)
    diag, _ = diagnose_rig(read_recording(path), SIM, DESIGN, accuracy=accuracy)
    causes = [f for f in diag.findings if f.effect not in ("model_form",)]
    assert [str(f.effect) for f in causes] == ["crosstalk"], diag.summary()
    if accuracy == "exact":
        assert causes[0].location == "load:x"
        assert causes[0].parameters["eps_z_rad"] == pytest.approx(eps, rel=0.05)
        assert "plumb line" in diag.summary()
    else:
        assert set(causes[0].location.split("|")) == {"load:x", "sensor:x"}
        assert "a tilted load line only in its own" in diag.summary()


def test_a_tilted_gauge_is_still_named_at_the_gauge(tmp_path):
    """The converse: a z gauge tilted towards x (read under every load axis) stays crosstalk at ``sensor:z``."""
    model = RigModel(SIM.C_F, {"crosstalk": {"sensor": "z", "eps_x_rad": 0.03}}, noise_mm=0.0006,
                     resolution_mm=0.0001, seed=6, places=joint_places(DESIGN.tool_mm, DESIGN))
    path = simulate_recording(model, LoadSchedule(repeats=3, hold_s=6.0), tmp_path / "gauge.rig.csv",
                              rod=DESIGN.name)
    diag, _ = diagnose_rig(read_recording(path), SIM, DESIGN, accuracy="exact")
    assert [(str(f.effect), f.location) for f in diag.findings] == [("crosstalk", "sensor:z")], diag.summary()
