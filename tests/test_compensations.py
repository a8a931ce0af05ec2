"""The compensation interface and the rod as one value: the registry feeds the help and the docs table, a new
compensation is one class that identification and the simulator take as they take the built-in ones, and the rod's
deflection through the interface is the deflection of its compliance file, number for number."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.cli.main import build_parser
from rodlab.calibrate import (COMPENSATIONS, CalibrationError, Compensation, FitOptions, ModelParams, Observations,
                              Rod, RodDeflection, ThermalGrowth, ball_positions, deflection_offsets, identify,
                              resolve_robot)
from rodlab.calibrate import PointSet
from rodlab.calibrate import compensations as registry
from rodlab.calibrate.points import points_observations
from rodlab.calibrate.simulate import simulate_campaign
from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method


@dataclass(frozen=True)
class Sag(Compensation):
    """A made-up compensation for the test: the ball sinks by ``k`` mm per unit of sin(q2) along -z of {W}."""

    name: ClassVar[str] = "sag"
    summary: ClassVar[str] = "a test sag"
    needs: ClassVar[str] = "nothing"
    option: ClassVar[str] = "`--sag`"
    k_mm: float = 0.05
    label: str = "sag"

    def offsets(self, robot, params, at) -> np.ndarray:
        out = np.zeros((at.q_rad.shape[0], 3))
        out[:, 2] = -self.k_mm * np.sin(at.q_rad[:, 1])
        return out


def test_the_registry_feeds_the_docs_table_and_the_help(monkeypatch):
    assert list(COMPENSATIONS) == ["rod_deflection", "thermal_growth"]
    table = registry.compensations_markdown()
    assert all(f"| `{name}` |" in table for name in COMPENSATIONS)
    doc = (Path(__file__).resolve().parents[1] / "docs" / "calibrate.md").read_text(encoding="utf-8")
    assert table in doc                                              # generated (scripts/gen_cli_docs.py)
    monkeypatch.setitem(COMPENSATIONS, Sag.name, Sag)                # a new entry shows up without another edit
    assert "| `sag` | a test sag | nothing | `--sag` |" in registry.compensations_markdown()
    assert "sag: --sag" in registry.compensations_help()
    text = build_parser()._subparsers._group_actions[0].choices["calibrate"].format_help()
    assert "sag" in " ".join(text.split())


def test_a_new_compensation_is_removed_by_identification():
    """Instrument points whose ball sinks with sin(q2) (not a kinematic error): the rigid model leaves it in
    the residuals; the new compensation, given like the built-in ones, removes it down to the noise."""
    robot = resolve_robot("ur5")
    rng = np.random.default_rng(4)
    tool = [20.0, 10.0, 150.0]
    true = ModelParams.nominal(robot, tool, base=[1500.0, 200.0, -300.0, 0.5, -0.3, 30.0])
    q = np.deg2rad(rng.uniform(-80, 80, (80, 6)))
    sag = Sag(0.2)
    x = ball_positions(robot, true, q)[0].pW + sag.offsets(robot, true, Observations(q, q[:, :3], q[:, :3]))
    obs = Observations(q, x + rng.normal(0, 0.005, x.shape), np.zeros((80, 3)))
    options = FitOptions(freed={"tool_y"}, pinned={f"c_{i}": 0.0 for i in range(2, 7)}, expected_noise_mm=None)
    plain = identify(robot, obs, Rod.rigid(tool), options=options)
    fixed = identify(robot, obs, Rod.rigid(tool), [sag], options)
    assert plain.rms_mm > 3 * fixed.rms_mm and fixed.rms_mm < 0.007
    np.testing.assert_allclose(fixed.offsets_W_mm, sag.offsets(robot, true, obs))


def test_the_simulator_takes_compensations_and_refuses_the_deflection(tmp_path):
    robot, rod = resolve_robot("tx90"), calc_rod_compliance(resolve_design("rod4"))
    with pytest.raises(CalibrationError, match="rod_true"):
        simulate_campaign(robot, rod, tmp_path / "a", compensations=[RodDeflection.of(rod)])
    with pytest.raises(CalibrationError, match="not a compensation"):
        simulate_campaign(robot, rod, tmp_path / "b", compensations=["thermal"])
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()


def test_rod_is_the_compliance_files_rod():
    rc = calc_rod_compliance(resolve_design("rod1"))
    rod = Rod.of(rc)
    assert rod.method is Method.CALC and rod.deflects and rod.mass_kg == rc.mass_kg and rod.name == rc.rod
    np.testing.assert_array_equal(rod.tool_mm, rc.tool_mm)
    np.testing.assert_array_equal(rod.com_T_mm, rc.com_T_mm)
    g, F = np.array([[0.0, 0.3, -0.95]]), np.array([[1.1, 1.25, 1.05]])
    np.testing.assert_array_equal(rod.offset_T_mm(g, F), rc.offset_T_mm(g, F))
    robot = resolve_robot("tx90")
    p = ModelParams.nominal(robot, rc.tool_mm)
    q = np.deg2rad([[0, 10, 90, 0, 30, 0], [40, -20, 100, 30, -40, 60]])
    at = Observations(q, np.zeros((2, 3)), np.tile(F, (2, 1)), Rod.of(rc))
    np.testing.assert_array_equal(RodDeflection.of(rc).offsets(robot, p, at),
                                  deflection_offsets(robot, p, q, at.force_W_N, rc))
    none = RodDeflection.of(RodCompliance.none_like(rc))
    assert not none.active and none.label == "none" and not none.offsets(robot, p, at).any()
    assert not Rod.rigid([0.0, 0.0, 100.0]).deflects


def test_the_rod_travels_with_the_observations_and_its_weight_bends_the_joints():
    """The observations carry the rod they were measured with (the compliance file's, an instrument's payload),
    and its weight is what loads the joints: the points move by the rod's weight on compliant joints, as
    ball_positions with that rod moves them; a rod given as loose numbers is refused."""
    rc = calc_rod_compliance(resolve_design("rod1"))
    robot = resolve_robot("tx90")
    p = ModelParams.nominal(robot, rc.tool_mm).with_(c=np.r_[0.0, np.full(5, 2e-6)])
    q = np.deg2rad([[0, 10, 90, 0, 30, 0], [40, -20, 100, 30, -40, 60]])
    F = np.tile([1.1, 1.25, 1.05], (2, 1))
    heavy = Observations(q, np.zeros((2, 3)), F, Rod.of(rc))
    light = Observations(q, np.zeros((2, 3)), F)
    np.testing.assert_array_equal(heavy.balls(robot, p)[0].pW, ball_positions(robot, p, q, Rod.of(rc), force_W_N=F)[0].pW)
    sag = np.linalg.norm(heavy.balls(robot, p)[0].pW - light.balls(robot, p)[0].pW, axis=1)
    assert np.all(sag > 1e-3)                                   # 2 urad/(N m) joints under a rod of ~1 kg
    rigid = Rod.rigid(rc.tool_mm, rc.mass_kg, rc.com_T_mm)       # the weight alone: the same load
    np.testing.assert_array_equal(ball_positions(robot, p, q, rigid, force_W_N=F)[1], heavy.balls(robot, p)[1])
    assert heavy.subset(np.array([True, False])).rod is heavy.rod
    pts = PointSet(np.rad2deg(q), np.zeros((2, 3)), rc.tool_mm, 0.8, np.array([0.0, 0.0, -50.0]))
    probe = points_observations(pts).rod                         # an instrument's probe: the file's tool and payload
    assert probe.mass_kg == 0.8 and not probe.deflects and np.array_equal(probe.com_T_mm, [0.0, 0.0, -50.0])
    np.testing.assert_array_equal(probe.tool_mm, rc.tool_mm)
    with pytest.raises(TypeError, match="Rod.rigid"):
        Observations(q, np.zeros((2, 3)), F, rc.mass_kg)


@pytest.mark.parametrize("kw, key", [({"tool_mm": [1.0, 2.0]}, "tool_mm"), ({"mass_kg": -1.0}, "mass_kg"),
                                     ({"C_F": np.eye(2)}, "C_F"), ({"com_T_mm": [0, 0, np.nan]}, "com_T_mm")])
def test_rod_refuses_bad_values(kw, key):
    args = {"tool_mm": [0.0, 0.0, 100.0]} | kw
    with pytest.raises(CalibrationError) as e:
        Rod(**args)
    assert e.value.key == key


def test_identify_takes_a_rod_and_labels_join():
    robot = resolve_robot("tx90")
    obs = Observations(np.zeros((8, 6)), np.zeros((8, 3)), np.zeros((8, 3)))
    with pytest.raises(TypeError, match="Rod.of"):
        identify(robot, obs, [0.0, 0.0, 100.0])
    th = ThermalGrowth(np.array([0.0, 0.0, 0.01]))
    assert registry.compensation_label([RodDeflection.of(None), th]) == "none+thermal"
    assert registry.compensation_label([]) == "none"
