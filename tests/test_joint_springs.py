"""Compliant joints a design declares (rodlab.rod/2 ``[joints.PLACE]``, #43): the springs' physics in C_F and
C_g, the file format, and `rodlab update` fitting a joint's compliance the recording measures."""
import re
import subprocess
import sys

import numpy as np
import pytest

from conftest import legacy_design, legacy_file
from rodlab.app.diagnose import diagnose_rig
from rodlab.app.update import Measured, update_design
from rodlab.core.calc import calc_compliance
from rodlab.core.compliance import RodCompliance
from rodlab.core.design_io import design_from_dict, design_to_dict, load_design
from rodlab.core.errors import DesignError, FormatError
from rodlab.fea.frame import frame_compliance
from rodlab.core.joint_springs import JointSpring, design_joint_places
from rodlab.core.massprops import distal_mass_properties, mass_properties
from rodlab.core.sensitivity import with_values
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.effects import joint_places
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording
from rodlab.core.units import G0

ROD1 = legacy_design("rod1")
S = 4e-6          # rad/(N m)


def _straight():
    data = design_to_dict(ROD1)
    data.update(gamma_deg=180.0, L2_mm=400.0)
    return design_from_dict(data)


def test_a_clamp_spring_on_a_straight_rod_is_a_hinge():
    """A rotational spring at the flange of a straight rod: the ball moves s L^2 per N across the rod and nothing
    along it; under its own weight across the rod, s (m g0 z_com) L, with the whole rod's mass and centre of mass."""
    d = _straight()
    soft = with_values(d, {"joints.flange_clamp.s_bend_rad_per_Nm": S})
    dF = calc_compliance(soft)[0] - calc_compliance(d)[0]
    dg = calc_compliance(soft)[1] - calc_compliance(d)[1]
    place = design_joint_places(d)["flange_clamp"]
    L = -place.point_T_mm[2]                     # clamp to ball centre along the rod [mm]
    s = S * 1e-3                                 # rad/(N mm)
    assert dF[0, 0] == pytest.approx(s * L * L, rel=1e-9) and dF[1, 1] == pytest.approx(s * L * L, rel=1e-9)
    assert abs(dF[2, 2]) < 1e-12 * dF[0, 0]
    mp = mass_properties(d)
    arm = mp.com_T_mm[2] - place.point_T_mm[2]
    assert dg[0, 0] == pytest.approx(s * mp.mass_kg * G0 * arm * L, rel=1e-6)
    np.testing.assert_allclose(dF, dF.T, atol=1e-15)


def test_the_frame_and_the_closed_form_add_the_same_spring():
    soft = with_values(ROD1, {"joints.ring_1.s_bend_rad_per_Nm": S, "joints.pipe_II.s_torsion_rad_per_Nm": S})
    for fn in (lambda x: calc_compliance(x), frame_compliance):
        dF = fn(soft)[0] - fn(ROD1)[0]
        dg = fn(soft)[1] - fn(ROD1)[1]
        np.testing.assert_allclose(dF, calc_compliance(soft)[0] - calc_compliance(ROD1)[0], rtol=1e-9, atol=1e-15)
        np.testing.assert_allclose(dg, calc_compliance(soft)[1] - calc_compliance(ROD1)[1], rtol=1e-9, atol=1e-15)
        assert np.all(np.linalg.eigvalsh(dF) > -1e-15)              # a spring only softens


def test_distal_mass_runs_from_the_whole_rod_to_the_ball():
    whole, ball_only = distal_mass_properties(ROD1, 0.0), distal_mass_properties(ROD1, 1e6)
    mp = mass_properties(ROD1)
    assert whole.mass_kg == pytest.approx(mp.mass_kg, rel=1e-9)
    np.testing.assert_allclose(whole.com_T_mm, mp.com_T_mm, atol=1e-6)
    from rodlab.core.massprops import ball_mass_properties
    assert ball_only.mass_kg == pytest.approx(ball_mass_properties(ROD1).mass_kg, rel=1e-9)
    mid = distal_mass_properties(ROD1, design_joint_places(ROD1)["ring_1"].s_mm)
    assert ball_only.mass_kg < mid.mass_kg < whole.mass_kg


def test_rod2_round_trip_and_errors(tmp_path):
    soft = with_values(ROD1, {"joints.ring_1.s_bend_rad_per_Nm": S})
    data = design_to_dict(soft)
    assert data["format"] == "rodlab.rod/2" and design_from_dict(data) == soft
    assert design_to_dict(ROD1)["format"] == "rodlab.rod/1"
    assert soft != ROD1 and soft.joints == {"ring_1": JointSpring(S, 0.0)}
    src = legacy_file(tmp_path / "rod1.rod.toml", "rod1").read_text()
    bad = tmp_path / "bad.rod.toml"
    bad.write_text(src + "\n[joints.ring_1]\ns_bend_rad_per_Nm = 2e-6\n")
    with pytest.raises(FormatError, match="rodlab.rod/2"):
        load_design(bad)
    v2 = src.replace('"rodlab.rod/1"', '"rodlab.rod/2"')
    for extra, words in (("[joints.ring_2]\ns_bend_rad_per_Nm = 2e-6\n", "ring_1"),
                         ("[joints.ring_1]\ns_bend = 2e-6\n", "s_bend_rad_per_Nm"),
                         ("[joints.ring_1]\ns_bend_rad_per_Nm = -1e-6\n", "non-negative")):
        bad.write_text(v2 + "\n" + extra)
        with pytest.raises(DesignError, match=words) as e:
            load_design(bad)
        assert e.value.line is not None
    ok = tmp_path / "ok.rod.toml"
    ok.write_text(v2 + "\n[joints.ring_1]\ns_bend_rad_per_Nm = 4e-6\n")
    assert load_design(ok).joints["ring_1"].s_bend_rad_per_Nm == S
    run = subprocess.run([sys.executable, "-m", "rodlab", "validate", str(ok)], capture_output=True, text=True)
    assert run.returncode == 0 and "rodlab.rod/2" in run.stdout


def _recording(tmp_path, true, seed=3):
    C = frame_compliance(true)[0]
    model = RigModel(C, {"friction": {"F_f_N": 0.2}}, noise_mm=0.0006, seed=seed,
                     places=joint_places(ROD1.tool_mm, ROD1))
    simulate_recording(model, LoadSchedule(), tmp_path / "rec.rig.csv", rod="1#")
    return read_recording(tmp_path / "rec.rig.csv")


def _frame_sim(design):
    return RodCompliance.from_design(design, *frame_compliance(design), "fea", {"model": "frame"})


def test_update_fits_a_joint_beyond_tolerance_and_the_as_built_design_explains_it(tmp_path):
    """A ring bond 60x softer than a sound one is located by the diagnosis; `update --free` on its compliance
    recovers it; against the as-built design's simulation only the rig's friction is left (and the rod within
    tolerance of it)."""
    true = with_values(ROD1, {"joints.ring_1.s_bend_rad_per_Nm": 6e-5})
    rec = _recording(tmp_path, true)
    diag, model = diagnose_rig(rec, _frame_sim(ROD1), ROD1)
    assert "joint_compliance" in {f.effect for f in diag.findings}
    lin = model.linear
    res = update_design(ROD1, Measured(lin.entries, lin.C, lin.cov, "rec"), ["joints.ring_1.s_bend_rad_per_Nm"])
    assert abs(res.x[0] - 6e-5) < 3 * res.sigma[0] and res.sigma[0] < 5e-6
    assert np.all(np.abs(res.r_after - 1) < 0.01)
    again, _ = diagnose_rig(rec, _frame_sim(res.design), res.design)
    assert {f.effect for f in again.findings} == {"friction", "model_form"}


def test_update_cli_declares_the_joint(tmp_path):
    true = with_values(ROD1, {"joints.ring_1.s_bend_rad_per_Nm": 6e-5})
    rec = _recording(tmp_path, true, seed=4)
    rod1 = legacy_file(tmp_path / "rod1.rod.toml", "rod1")
    out = tmp_path / "asbuilt.rod.toml"
    cmd = [sys.executable, "-m", "rodlab", "update", str(rod1), "--measured", str(rec.path if hasattr(rec, "path")
           else tmp_path / "rec.rig.csv"), "-o", str(out)]
    refused = subprocess.run(cmd, capture_output=True, text=True)
    assert refused.returncode == 3 and "rodlab update: refused:" in refused.stderr and not out.exists()   # good files
    assert re.search(r"--free \S*joints\.ring_1\.s_bend_rad_per_Nm\)", refused.stderr), refused.stderr
    typo = subprocess.run(cmd + ["--free", "joints.ring_2.s_bend_rad_per_Nm"], capture_output=True, text=True)
    assert typo.returncode == 2 and "Did you mean `joints.ring_1.s_bend_rad_per_Nm`" in typo.stderr and not out.exists()
    run = subprocess.run(cmd + ["--free", "joints.ring_1.s_bend_rad_per_Nm"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    built = load_design(out)
    assert "rodlab.rod/2" in out.read_text() and "design: 0" in out.read_text()
    assert built.joints["ring_1"].s_bend_rad_per_Nm == pytest.approx(6e-5, rel=0.1)


def test_validate_names_the_format_line_for_joints_in_a_v1_file(tmp_path):
    src = legacy_file(tmp_path / "rod1.rod.toml", "rod1").read_text()
    bad = tmp_path / "v1.rod.toml"
    bad.write_text(src + "\n[joints.ring_1]\ns_bend_rad_per_Nm = 2e-6\n")
    run = subprocess.run([sys.executable, "-m", "rodlab", "validate", str(bad)], capture_output=True, text=True)
    assert run.returncode != 0 and 'format = "rodlab.rod/2"' in run.stdout + run.stderr


def test_update_accepts_a_freed_joint_of_a_group_and_a_freed_modulus_for_a_scale():
    """A diagnosis that cannot tell two places apart names the group (``pipe_II|ring_1``); freeing either joint is
    what its own refusal suggests, and must be accepted (it was refused again); a compliance scale is what a freed
    modulus E fits, a torsion what a freed G fits."""
    from types import SimpleNamespace as F

    from rodlab.app.cli.update_measured import _explained_by_keys
    tube = ROD1.pipe_I.material.name
    group = F(effect="joint_compliance", location="pipe_II|ring_1")
    assert _explained_by_keys(group, ["joints.pipe_II.s_bend_rad_per_Nm"], ROD1)
    assert _explained_by_keys(group, ["joints.ring_1.s_bend_rad_per_Nm"], ROD1)
    assert not _explained_by_keys(group, ["joints.flange_clamp.s_bend_rad_per_Nm", f"materials.{tube}.E_GPa"], ROD1)
    scale, twist = F(effect="compliance_scale", location=None), F(effect="torsion_compliance", location="pipe_I")
    assert _explained_by_keys(scale, [f"materials.{tube}.E_GPa"], ROD1)
    assert not _explained_by_keys(scale, [f"materials.{tube}.G_GPa"], ROD1)
    assert not _explained_by_keys(scale, [f"materials.{ROD1.ball.material.name}.E_GPa"], ROD1)   # not the tubes'
    assert _explained_by_keys(twist, [f"materials.{tube}.G_GPa"], ROD1)


def test_update_does_not_overwrite_the_design_it_starts_from(tmp_path):
    rod1 = legacy_file(tmp_path / "rod1.rod.toml", "rod1")
    before = rod1.read_text()
    rec = _recording(tmp_path, ROD1, seed=5)
    run = subprocess.run([sys.executable, "-m", "rodlab", "update", str(rod1), "--measured",
                          str(rec.path if hasattr(rec, "path") else tmp_path / "rec.rig.csv"), "-o", str(rod1)],
                         capture_output=True, text=True)
    assert run.returncode == 2 and "is the design itself" in run.stderr and "Traceback" not in run.stderr
    assert rod1.read_text() == before
