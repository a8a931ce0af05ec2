"""Friction and a tare whose weight equals it move only the unloading branch: a hysteresis of a bond or clamped joint
does the same (a blind tester's bow-shaped hysteresis had been friction and a tare, both "decisive", with no word
of it). The diagnosis says so with both findings; a friction and tare of different sizes get no such caution."""
from __future__ import annotations

import pytest

from rodlab import calc_rod_compliance
from rodlab.app.diagnose import diagnose_rig
from rodlab.core.design_io import resolve_design
from rodlab.core.units import G0
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

DESIGN = resolve_design("rod1")
SIM = calc_rod_compliance(DESIGN)


@pytest.mark.parametrize("tare_N, said", [(1.0, True), (0.4, False)])
def test_an_unloading_branch_shifted_alone_is_said_to_be_a_hysteresis_too(tmp_path, tare_N, said):
    model = RigModel(SIM.C_F, {"friction": {"F_f_N": 1.0}, "tare": {"tare_kg": tare_N / G0}}, noise_mm=0.0005,
                     resolution_mm=0.0001, seed=8)
    path = simulate_recording(model, LoadSchedule(repeats=3, hold_s=4.0), tmp_path / "r.rig.csv", rod=DESIGN.name)
    diag, _ = diagnose_rig(read_recording(path), SIM, DESIGN)
    found = {f.effect: f for f in diag.findings}
    assert "friction" in found and "tare" in found, diag.summary()
    cautions = [f.evidence.get("caution") or "" for f in (found["friction"], found["tare"])]
    assert all("the loading branch has not moved" in c for c in cautions) == said, diag.summary()
    assert any("the loading branch has not moved" in c for c in cautions) == said
