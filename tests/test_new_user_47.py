"""What a new-user trial (2026-11-29, an integrator calibrating with a laser tracker and URDF / modified-DH robots)
found, fixed: a calibration exported onto a robot description with other joint zeros (a model 6.8 mm wrong with a
passing read-back), a compliant calibration exported as a DH table without a word on the sag it leaves out, an
untrusted result exported with exit 0, sigma columns in um, a `# units: m` line and unknown quantity keys read past,
a xacro file `validate` could not name, the calibrated TCP link not named after a `--tip-link` export, and a
warning per mesh of a URDF copied away from its package."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from rodlab.app.cli.main import main
import numpy as np

from rodlab.calibrate import read_points, read_robot, resolve_robot, robot_path
from rodlab.calibrate.kinematics import ball_positions
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.readings import point_unit_slips
from rodlab.calibrate.result import calibrated_params, read_calibration
from rodlab.calibrate.sockets import read_sockets

DATA = Path(__file__).resolve().parents[1] / "benchmarks" / "data"


@pytest.fixture(scope="module")
def ur5(tmp_path_factory) -> tuple[Path, Path, Path]:
    """(every fourth UR5 grid pose, its kinematic-only and its full calibration result)."""
    tmp = tmp_path_factory.mktemp("ur5_47")
    lines = (DATA / "jacobi2025" / "ur5_grid.validation.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [next(ln for ln in lines if ln.startswith("q1"))]
    rows = [ln for ln in lines if ln and not ln.startswith(("#", "q1"))][::4]
    pts = tmp / "ur5.validation.csv"
    pts.write_text("\n".join(head + rows) + "\n")
    kin, full = tmp / "kin.json", tmp / "full.json"
    for out, extra in ((kin, ["--kinematic-only"]), (full, [])):
        main(["calibrate", "--points", str(pts), "--robot", "ur5", "--fix-unidentifiable", "--json", str(out), *extra])
    return pts, kin, full


def test_a_result_records_its_description_and_export_re_references_other_joint_zeros(ur5, tmp_path, capsys):
    """The elbow's origin turned by 0.05 rad (its zero 2.9 deg off): the export had written a URDF 6.8 mm off the
    calibrated model and said 'read back: TCP within 1e-9 um'. The result records its description's zeros, and the
    offsets are re-referenced to the other description's: its model is the calibrated one, said in a note."""
    _, kin, _ = ur5
    cal = read_calibration(kin)
    assert cal.description is not None and len(cal.description["theta_offset_deg"]) == 6
    urdf = robot_path("ur5").read_text()
    moved = urdf.replace('<origin xyz="0 -0.1197 0.425" rpy="0 0 0"/>', '<origin xyz="0 -0.1197 0.425" rpy="0 0.05 0"/>')
    assert moved != urdf
    other = tmp_path / "ur5_zero3.urdf"
    other.write_text(moved)
    capsys.readouterr()
    assert main(["export", str(kin), "--urdf", str(other), "-o", str(tmp_path / "x.urdf")]) == 0
    err = capsys.readouterr().err
    assert "counts joints from other zeros" in err and "joint 3:" in err and "re-referenced" in err
    assert main(["export", str(kin), "-o", str(tmp_path / "ok.urdf")]) == 0             # its own description
    assert "other zeros" not in capsys.readouterr().err
    mine, theirs = resolve_robot("ur5"), read_robot(other)
    q = np.random.default_rng(1).uniform(-2.0, 2.0, (50, 6))
    p_own = ball_positions(mine, calibrated_params(mine, cal), q)[0].pW
    p_other = ball_positions(theirs, calibrated_params(theirs, cal), q)[0].pW
    np.testing.assert_allclose(p_other, p_own, atol=1e-6)                 # the same calibrated model
    yaml = (tmp_path / "x.yaml").read_text()                              # its dtheta_3 is this description's
    line = next(ln for ln in yaml.splitlines() if ln.strip().startswith("dtheta_3:"))
    assert "re-referenced to this description's zero" in line
    shift = float(theirs.theta_offset_deg[2] - mine.theta_offset_deg[2])
    written = float(line.split("value:")[1].split(",")[0])
    assert written == pytest.approx(cal.parameters["dtheta_3"].value - shift, abs=1e-6)


def test_a_result_without_its_description_is_exported_with_a_warning(ur5, tmp_path, capsys):
    _, kin, _ = ur5
    data = json.loads(kin.read_text())
    del data["description"]
    old = tmp_path / "old.json"
    old.write_text(json.dumps(data))
    capsys.readouterr()
    assert main(["export", str(old), "-o", str(tmp_path / "old.urdf")]) == 0
    assert "does not record the robot description" in capsys.readouterr().err


def test_a_compliant_result_exported_as_a_dh_table_is_warned_of(tmp_path, capsys, examples):
    """A DH robot (no URDF): the table alone leaves the gravity sag to the compliance; said as for a URDF."""
    camp = examples / "campaign-null"
    cal = tmp_path / "cal.json"
    main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
          "--rod", str(next(camp.glob("*.compliance.json"))), "--json", str(cal)])
    capsys.readouterr()
    main(["export", str(cal), "--robot", "tx90", "-o", str(tmp_path / "tx90")])
    err = capsys.readouterr().err
    assert "a consumer of the DH table that does not add the joint compliance" in err and "--kinematic-only" in err


def test_an_untrusted_result_exports_with_exit_3(ur5, tmp_path, capsys):
    _, kin, _ = ur5
    data = json.loads(kin.read_text())
    data["trusted"] = False
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps(data))
    assert main(["export", str(bad), "-o", str(tmp_path / "bad.urdf")]) == 3
    assert "NOT TRUSTED" in capsys.readouterr().err and (tmp_path / "bad.urdf").exists()


def test_points_sigmas_in_um_and_a_units_line_are_named(ur5, tmp_path):
    pts, _, _ = ur5
    lines = pts.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("q1"))
    um = lines[:i] + [lines[i] + ",sigma_x_mm,sigma_y_mm,sigma_z_mm"] + [ln + ",12,12,15" for ln in lines[i + 1:]]
    path = tmp_path / "um.validation.csv"
    path.write_text("\n".join(um) + "\n")
    assert any("look like um" in s for s in point_unit_slips(read_points(path), path))
    assert not point_unit_slips(read_points(path), path, sigmas=False)      # --noise-um replaces them: not judged
    assert not any("look like um" in s for s in point_unit_slips(read_points(pts), pts))
    units = tmp_path / "units.validation.csv"
    units.write_text("\n".join(lines[:i] + ["# units: m"] + lines[i:]) + "\n")
    with pytest.raises(CalibrationError, match="names m: rodlab reads the lengths as millimetres") as e:
        read_points(units)
    assert e.value.key == "units"
    for ok in ("mm", "mm, deg", "millimetres"):
        mm = tmp_path / "mm.validation.csv"
        mm.write_text("\n".join(lines[:i] + [f"# units: {ok}"] + lines[i:]) + "\n")
        assert len(read_points(mm).q_deg) == len(lines) - i - 1


def test_an_unknown_quantity_key_in_a_sockets_file_is_refused(tmp_path):
    src = DATA / "mukca2025" / "panda_2.sockets.csv"
    read_sockets(src, 7)
    text = src.read_text()
    keyed = tmp_path / "k.sockets.csv"
    keyed.write_text("# tool_offset_mm: 0, 0, 10\n" + text)
    with pytest.raises(CalibrationError, match="unknown key 'tool_offset_mm'"):
        read_sockets(keyed, 7)
    noted = tmp_path / "n.sockets.csv"
    noted.write_text("# Source: a note of the user's\n# units: mm\n" + text)
    read_sockets(noted, 7)
    for line in ("# Units: inch", "# UNITS: m", "# Tool_Offset_MM: 1, 2, 3"):
        bad = tmp_path / "b.sockets.csv"
        bad.write_text(line + "\n" + text)
        with pytest.raises(CalibrationError):
            read_sockets(bad, 7)


def test_validate_names_a_xacro_file(tmp_path, capsys):
    x = tmp_path / "arm.urdf.xacro"
    x.write_text('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="arm"><xacro:property name="l" '
                 'value="1"/></robot>')
    assert main(["validate", str(x)]) == 2
    assert "expand it first" in capsys.readouterr().err


def test_points_of_two_targets_in_one_file_are_named(tmp_path, capsys):
    """The public FANUC points of reflector N1 (poses 1-30) then N2 (31-59) in one file: refused at 156 mm with the
    joint columns, units and robot file as suspects, then named: each part fits the nominal model on its own."""
    def rows(name):
        lines = (DATA / "boby2021" / name).read_text().splitlines()
        i = next(k for k, ln in enumerate(lines) if ln.startswith("q1"))
        return lines[:i + 1], lines[i + 1:]
    head, n1 = rows("r2000ic_N1.validation.csv")
    _, n2 = rows("r2000ic_N2.validation.csv")
    mixed = tmp_path / "mixed.validation.csv"
    mixed.write_text("\n".join(head + n1[:30] + n2[30:]) + "\n")
    assert main(["calibrate", "--points", str(mixed), "--robot", "r2000ic165f"]) == 2
    err = capsys.readouterr().err
    assert "the target or tool changed at data row 31" in err
    assert main(["calibrate", "--points", str(DATA / "boby2021" / "r2000ic_N2.validation.csv"), "--robot",
                 "r2000ic165f"]) in (0, 3)
    assert "target or tool changed" not in capsys.readouterr().err


def test_a_tracker_export_keeps_its_names_and_time_stamps(ur5, tmp_path, capsys):
    """point_name and timestamp columns (a trial: refused, names lost for tracing) are kept and not read; any other
    unknown column is still refused."""
    pts, _, _ = ur5
    lines = pts.read_text().splitlines()
    i = next(k for k, ln in enumerate(lines) if ln.startswith("q1"))
    rows = [f"P{k:04d},2025-03-01T10:00:{k % 60:02d}," + ln for k, ln in enumerate(lines[i + 1:])]
    named = tmp_path / "named.validation.csv"
    named.write_text("\n".join(lines[:i] + ["point_name,timestamp," + lines[i]] + rows) + "\n")
    got, plain = read_points(named), read_points(pts)
    np.testing.assert_array_equal(got.x_W_mm, plain.x_W_mm)
    assert main(["validate", str(named)]) == 0
    other = tmp_path / "other.validation.csv"
    other.write_text("\n".join(lines[:i] + ["remark," + lines[i]] + ["x," + ln for ln in lines[i + 1:]]) + "\n")
    with pytest.raises(CalibrationError, match="unknown column 'remark'"):
        read_points(other)
