"""Names that meant two things got one each: ``diagnose --rig --design`` (``--rod`` is a compliance file
everywhere, its old rig meaning still read with a warning), the FEA's stiffness assembly beside the CAD
assembly, the frame's joint fit beside the robot's calibration."""
from __future__ import annotations

import importlib
import json

import pytest

from rodlab import calc_rod_compliance, resolve_design, write_compliance
from rodlab.app.cli.main import main


@pytest.fixture(scope="module")
def rig_files(tmp_path_factory):
    """A rod 3# recording with friction, and its closed-form simulation."""
    from rodlab.stiffness_rig.model import LoadSchedule, RigModel
    from rodlab.stiffness_rig.simulate import simulate_recording
    tmp = tmp_path_factory.mktemp("rig")
    design = resolve_design("rod3")
    sim = calc_rod_compliance(design)
    rec = tmp / "r.rig.csv"
    simulate_recording(RigModel(sim.C_F, {"friction": {}}, noise_mm=0.001, resolution_mm=0.001, seed=5),
                       LoadSchedule(axes=("z", "x", "y"), repeats=2, hold_s=5.0, masses=(0.5, 1.0)), rec,
                       rod=design.name)
    return rec, write_compliance(sim, tmp / "sim.compliance.json")


def test_diagnose_rig_takes_the_design_as_design_and_the_old_rod_with_a_warning(rig_files, tmp_path, capsys):
    rec, sim = rig_files
    base = ["diagnose", "--rig", str(rec), "--sim", str(sim)]
    assert main([*base, "--design", "rod3", "--json", str(tmp_path / "new.json")]) == 0
    assert "deprecated" not in capsys.readouterr().err
    assert main([*base, "--rod", "rod3", "--json", str(tmp_path / "old.json")]) == 0
    err = capsys.readouterr().err
    assert "--rod with --rig is deprecated" in err and "--design rod3" in err
    new, old = (json.loads((tmp_path / f).read_text()) for f in ("new.json", "old.json"))
    assert new == old and new["findings"][0]["effect"] == "friction"
    assert main([*base, "--rod", "rod3", "--design", "rod3"]) == 2
    assert "old spelling of --design" in capsys.readouterr().err


def test_diagnose_help_names_the_design_and_the_compliance_apart(capsys):
    with pytest.raises(SystemExit):
        main(["diagnose", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "--design DESIGN rig: the *.rod.toml design" in out
    assert "--rod ROD campaign: the *.compliance.json used" in out


def test_campaign_refuses_a_design_option(tmp_path, capsys):
    assert main(["diagnose", "--campaign", str(tmp_path / "c.csv"), "--fixture", "f.json", "--rod", "r.json",
                 "--design", "rod1"]) == 2
    assert "--design is the rig's design" in capsys.readouterr().err


def test_fea_names_its_stiffness_assembly_and_joint_fit_apart_from_geometry_and_calibration():
    import rodlab.fea as fea
    from rodlab.fea import family, joints
    assert importlib.import_module("rodlab.fea.stiffness_assembly").assemble_stiffness
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("rodlab.fea.assembly")
    assert fea.JointFit is joints.JointFit and fea.fit_joints is joints.fit_joints
    assert family.joint_fit_member(resolve_design("rod1")).name == resolve_design("rod1").name
    # the old names still work for callers (the design study)
    assert fea.JointCalibration is fea.JointFit and fea.calibrate_joints is fea.fit_joints
    assert family.calibration_member is family.joint_fit_member
