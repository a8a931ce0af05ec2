"""The calibrate / export defaults a calibration engineer meets first: instrument points name their robot, a
built-in URDF robot is written back without --urdf, and a consumer that cannot add joint compliance is told
how to get the geometry it needs (--kinematic-only)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from rodlab.app.cli.main import main

DATA = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "jacobi2025"


@pytest.fixture(scope="module")
def ur5_points(tmp_path_factory) -> Path:
    """Every fourth grid pose of the public UR5 tracker data (250 poses)."""
    lines = (DATA / "ur5_grid.validation.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [next(ln for ln in lines if ln.startswith("q1"))]
    rows = [ln for ln in lines if ln and not ln.startswith(("#", "q1"))][::4]
    path = tmp_path_factory.mktemp("ur5") / "ur5.validation.csv"
    path.write_text("\n".join(head + rows) + "\n")
    return path


def test_points_without_a_robot_are_refused(ur5_points, capsys):
    assert main(["calibrate", "--points", str(ur5_points), "--fix-unidentifiable"]) == 2
    assert "name the robot that made these readings with --robot" in capsys.readouterr().err


def test_kinematic_only_and_the_export_of_a_builtin_urdf_robot(ur5_points, tmp_path, capsys):
    full, kin = tmp_path / "full.json", tmp_path / "kin.json"
    for out, extra in ((full, []), (kin, ["--kinematic-only"])):
        main(["calibrate", "--points", str(ur5_points), "--robot", "ur5", "--fix-unidentifiable", "--json", str(out),
              *extra])
    params = json.loads(kin.read_text())["parameters"]
    assert all(params[f"c_{i}"]["value"] == 0.0 and params[f"c_{i}"]["status"] == "fixed" for i in range(2, 7))
    assert json.loads(full.read_text())["parameters"]["c_2"]["value"] > 1e-6
    capsys.readouterr()
    assert main(["export", str(full), "-o", str(tmp_path / "full.urdf")]) == 0      # robot from the file, URDF too
    io = capsys.readouterr()
    assert (tmp_path / "full.urdf").exists() and "calibrate again with --kinematic-only" in io.err
    assert main(["export", str(kin), "-o", str(tmp_path / "kin.urdf")]) == 0
    io = capsys.readouterr()
    assert (tmp_path / "kin.urdf").exists() and "--kinematic-only" not in io.err and "not in the URDF" not in io.out
    assert main(["export", str(full), "--robot", "ur10", "-o", str(tmp_path / "x.urdf")]) == 2
    assert "it names 'ur5'" in capsys.readouterr().err


def test_points_png_draws_the_validation_error_distributions(ur5_points, tmp_path, capsys):
    assert main(["calibrate", "--points", str(ur5_points), "--robot", "ur5", "--fix-unidentifiable",
                 "--validate", str(DATA / "ur5_random.validation.csv"), "--png", str(tmp_path / "fig")]) in (0, 3)
    assert (tmp_path / "fig" / "error_distributions.png").stat().st_size > 10_000
    main(["calibrate", "--points", str(ur5_points), "--robot", "ur5", "--fix-unidentifiable", "--png",
          str(tmp_path / "none")])
    assert "give --validate" in capsys.readouterr().err and not (tmp_path / "none").exists()


def test_the_last_joint_offset_is_said_to_carry_the_rod_twist(examples, tmp_path, capsys):
    """A campaign's dtheta_6 (the robot's zero plus the rod's mounting twist, which one rod cannot separate): the
    export says so on stderr and beside it in the YAML; -o X.urdf with a DH robot says no URDF was written."""
    camp = examples / "campaign-null"
    cal = tmp_path / "cal.json"
    assert main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
                 "--rod", str(camp / "rod1.compliance.json"), "--robot", "tx90", "--json", str(cal)]) in (0, 3)
    data = json.loads(cal.read_text())
    assert data["parameters"]["dtheta_6"]["status"] == "identified"
    data["parameters"]["dtheta_6"]["value"] = 0.15                  # a rod mounted 0.15 deg turned on the flange
    cal.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["export", str(cal), "--robot", "tx90", "-o", str(tmp_path / "tx90.urdf")]) == 0
    err = capsys.readouterr().err
    assert "dtheta_6 = +0.1500 deg" in err and "mounting twist" in err and "no URDF written" in err
    yaml = (tmp_path / "tx90.yaml").read_text()
    assert next(ln for ln in yaml.splitlines() if ln.strip().startswith("dtheta_6:")).endswith("separate them)")
