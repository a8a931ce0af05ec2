"""Numbers no MultiCal campaign, rod or fixture has are named as the unit slip that gives them, with the fix: joint
angles in radians, readings in um (refused: the calibration would be meaningless), a compliance file in um/N, a
mass in grams, a tool vector in metres, contact forces 100x (warned of). A robot file with another number of
joints than the campaign's columns is named as that."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from rodlab.app.cli import main
from rodlab.calibrate import read_campaign, read_fixture
from rodlab.calibrate.readings import unit_slips
from rodlab.core.compliance import read_compliance


@pytest.fixture(scope="module")
def camp(tmp_path_factory):
    folder = tmp_path_factory.mktemp("camp")
    assert main(["fea", "rod1", "--model", "calc", "-o", str(folder / "rod1.compliance.json")]) == 0
    assert main(["simulate-campaign", "--rod", str(folder / "rod1.compliance.json"), "-o", str(folder / "c")]) == 0
    return folder


def _scaled(src, dst, columns, factor):
    lines = src.read_text().splitlines()
    head = next(i for i, s in enumerate(lines) if not s.startswith("#"))
    cols = lines[head].split(",")
    out = lines[:head + 1]
    for line in lines[head + 1:]:
        cells = line.split(",")
        out.append(",".join(f"{float(c) * factor:.9g}" if cols[i] in columns else c for i, c in enumerate(cells)))
    dst.write_text("\n".join(out) + "\n")
    return dst


def _calibrate(camp, campaign, rod=None, fixture=None):
    return main(["calibrate", str(campaign), "--fixture", str(fixture or camp / "c" / "multical.fixture.json"),
                 "--rod", str(rod or camp / "rod1.compliance.json")])


def test_the_simulated_campaign_has_no_unit_slip(camp):
    path = camp / "c" / "multical.campaign.csv"
    assert unit_slips(read_campaign(path), path) == []


@pytest.mark.parametrize("columns,factor,message", [
    (("q1", "q2", "q3", "q4", "q5", "q6"), np.pi / 180, "look like radians"),
    (("x_mm", "y_mm", "z_mm"), 1000.0, "look like um"),
])
def test_campaign_columns_in_other_units_are_refused(camp, tmp_path, capsys, columns, factor, message):
    bad = _scaled(camp / "c" / "multical.campaign.csv", tmp_path / "bad.campaign.csv", columns, factor)
    assert _calibrate(camp, bad) == 2
    err = capsys.readouterr().err
    assert message in err and "bad.campaign.csv" in err and "Traceback" not in err


@pytest.mark.parametrize("edit,message", [
    (lambda d: d.update(C_F_mm_per_N=(np.array(d["C_F_mm_per_N"]) * 1000).tolist()), "divide C_F by 1000"),
    (lambda d: d.update(mass_kg=674.0), "if this is grams"),             # a 674 g rod
    (lambda d: d.update(tool_mm=(np.array(d["tool_mm"]) / 1000).tolist()), "if this is metres"),
])
def test_a_compliance_file_in_other_units_is_warned_of(camp, tmp_path, caplog, edit, message):
    data = json.loads((camp / "rod1.compliance.json").read_text())
    edit(data)
    data.pop("c_rod_um", None)
    path = tmp_path / "bad.compliance.json"
    path.write_text(json.dumps(data))
    with caplog.at_level("WARNING"):
        read_compliance(path)
    assert message in caplog.text
    caplog.clear()
    with caplog.at_level("WARNING"):
        read_compliance(camp / "rod1.compliance.json")
    assert caplog.text == ""


def test_contact_forces_a_hundred_times_too_large_are_warned_of(camp, tmp_path, caplog):
    data = json.loads((camp / "c" / "multical.fixture.json").read_text())
    data["contact_force_N"] = [110.0, 125.0, 105.0]
    path = tmp_path / "f.fixture.json"
    path.write_text(json.dumps(data))
    with caplog.at_level("WARNING"):
        read_fixture(path)
    assert "contact_force_N [110.0, 125.0, 105.0]" in caplog.text


def test_a_robot_file_with_another_joint_count_is_named(camp, tmp_path, capsys):
    from conftest import ROOT
    text = (ROOT / "calibrate" / "robots" / "tx90.toml").read_text()
    five = text[:text.rindex("[[joint]]")]
    (tmp_path / "five.toml").write_text(five)
    code = main(["calibrate", str(camp / "c" / "multical.campaign.csv"), "--fixture",
                 str(camp / "c" / "multical.fixture.json"), "--rod", str(camp / "rod1.compliance.json"), "--robot",
                 str(tmp_path / "five.toml")])
    err = capsys.readouterr().err
    assert code == 2 and "6 joint columns (q1..q6) and the robot model 5 joints" in err and "--robot" in err



def test_units_checked_turns_the_refusal_into_a_warning(camp, tmp_path, capsys):
    """A campaign that really turns every joint by less than 6.3 deg is the user's to confirm: ``--units-checked``
    uses the numbers as they are, with the warning kept."""
    bad = _scaled(camp / "c" / "multical.campaign.csv", tmp_path / "small.campaign.csv", ("q1", "q2", "q3", "q4", "q5",
                                                                                          "q6"), np.pi / 180)
    code = main(["calibrate", str(bad), "--fixture", str(camp / "c" / "multical.fixture.json"),
                 "--rod", str(camp / "rod1.compliance.json"), "--units-checked"])
    err = capsys.readouterr().err
    assert "look like radians" in err and "used as they are" in err and "Traceback" not in err
    assert "error:" not in err.split("used as they are")[0]
    # a fit tens of mm off (radians read as degrees) is refused without five more identifications to cross-validate
    assert code == 3 and "no cross-validation: the fit itself leaves" in err


@pytest.mark.parametrize("columns,factor,message", [
    (("x_mm", "y_mm", "z_mm"), 1e-3, "look like metres"),
])
def test_campaign_readings_in_metres_are_refused(camp, tmp_path, capsys, columns, factor, message):
    bad = _scaled(camp / "c" / "multical.campaign.csv", tmp_path / "m.campaign.csv", columns, factor)
    assert _calibrate(camp, bad) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("columns,factor,message", [
    (("q1", "q2", "q3", "q4", "q5", "q6"), np.pi / 180, "look like radians"),
    (("x_mm", "y_mm", "z_mm"), 1e-3, "look like metres"),
])
def test_validation_points_in_other_units_are_refused(camp, tmp_path, capsys, columns, factor, message):
    bad = _scaled(camp / "c" / "multical.validation.csv", tmp_path / "bad.validation.csv", columns, factor)
    for argv in (["calibrate", str(camp / "c" / "multical.campaign.csv"), "--fixture",
                  str(camp / "c" / "multical.fixture.json"), "--rod", str(camp / "rod1.compliance.json"),
                  "--validate", str(bad)],
                 ["calibrate", "--points", str(bad), "--robot", "tx90"], ["diagnose", "--points", str(bad), "--robot", "tx90"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert message in err and "bad.validation.csv" in err and "Traceback" not in err


def test_gross_residuals_do_not_advise_a_larger_noise(camp, tmp_path, capsys):
    """Joint 2's sign flipped: residuals thousands of times the device's noise are files that do not fit together,
    not a noisier device: the advice names the joints, units and files, never --noise-um."""
    bad = _scaled(camp / "c" / "multical.campaign.csv", tmp_path / "q2.campaign.csv", ("q2",), -1.0)
    assert _calibrate(camp, bad) == 2                     # the mix-up named and refused, nothing written
    out = "".join(capsys.readouterr())
    assert "joint 2's readings run the other way" in out and "state it with --noise-um" not in out
    assert main(["calibrate", str(bad), "--fixture", str(camp / "c" / "multical.fixture.json"),
                 "--rod", str(camp / "rod1.compliance.json"), "--columns-checked"]) == 3
    out = "".join(capsys.readouterr())
    assert "not a noisier device" in out and "order, signs" in out
    assert "state it with --noise-um" not in out


@pytest.mark.parametrize("edit,message", [
    (lambda t: re.sub(r"(?m)^alpha_deg = (-?)90\.0", r"alpha_deg = \g<1>1.5708", t, count=1), "radians where degrees"),
    (lambda t: t.replace("a_mm = 425.0", "a_mm = 42500.0"), "beyond any industrial arm"),
])
def test_a_robot_file_in_other_units_is_warned_of(tmp_path, caplog, capsys, edit, message):
    """Every command reading the file warns of one twist at pi/2 as a number or a link no arm has, and `rodlab
    validate` lists the warning under the file; the built-in TX90 has none of them."""
    from rodlab.calibrate import read_robot
    from rodlab.calibrate.robot_formats import builtin_robots
    text = builtin_robots()["tx90"].read_text()
    (tmp_path / "r.toml").write_text(edit(text))
    read_robot(tmp_path / "r.toml")
    assert message in caplog.text
    assert main(["validate", str(tmp_path / "r.toml")]) == 0
    out = capsys.readouterr().out
    assert "r.toml: rodlab.robot/2, valid, but with 1 warning(s):" in out and message in out
    caplog.clear()
    (tmp_path / "ok.toml").write_text(text)
    read_robot(tmp_path / "ok.toml")
    assert not [r for r in caplog.records if r.levelname == "WARNING"]
    assert main(["validate", str(tmp_path / "ok.toml")]) == 0
    assert "warning" not in capsys.readouterr().out


@pytest.mark.parametrize("edit,message,key", [
    (lambda t: re.sub(r"(?m)^(d_mm|a_mm) = (-?[0-9.]+)", lambda m: f"{m.group(1)} = {float(m.group(2)) / 1000}", t),
     "metres where millimetres are expected; multiply them by 1000", "joint[1].d_mm"),
    (lambda t: re.sub(r"(?m)^alpha_deg = (-?)90\.0", r"alpha_deg = \g<1>1.5708", t), "radians where degrees are expected",
     "alpha_deg"),
])
def test_a_robot_file_in_radians_or_metres_is_refused(tmp_path, capsys, edit, message, key):
    """Twists at pi/2 on several joints, or every length in metres, are no arm (an IRB 4600 trial's alpha in radians
    had been a warning and a 590 mm calibration): refused with the file, line and key, and the fix."""
    from rodlab.calibrate.robot_formats import builtin_robots
    (tmp_path / "r.toml").write_text(edit(builtin_robots()["tx90"].read_text()))
    assert main(["validate", str(tmp_path / "r.toml")]) != 0
    err = capsys.readouterr().err
    assert message in err and "r.toml" in err and key in err and "line" in err


def test_a_compliance_file_in_um_per_n_is_refused_before_a_calibration_uses_it(camp, tmp_path, capsys, caplog):
    """A paper trial: the warning had been printed and the file then compensated (77 mm of residuals, the fixture
    blamed, the result written); now refused, nothing written, and --units-checked lets it through."""
    data = json.loads((camp / "rod1.compliance.json").read_text())
    data["C_F_mm_per_N"] = (np.array(data["C_F_mm_per_N"]) * 1000).tolist()
    data.pop("c_rod_um", None)
    bad = tmp_path / "um.compliance.json"
    bad.write_text(json.dumps(data))
    out = tmp_path / "cal.json"
    code = main(["calibrate", str(camp / "c" / "multical.campaign.csv"), "--fixture",
                 str(camp / "c" / "multical.fixture.json"), "--rod", str(bad), "--json", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "divide C_F by 1000" in err and "--units-checked" in err and not out.exists()
    assert err.count("divide C_F by 1000") == 1                    # said once: the refusal, not a warning before it
    assert "divide C_F by 1000" not in caplog.text
    code = main(["compare", str(camp / "c" / "multical.campaign.csv"), "--fixture",
                 str(camp / "c" / "multical.fixture.json"), "--rod", f"fea={bad}", "--validate",
                 str(camp / "c" / "multical.validation.csv")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("divide C_F by 1000") == 1 and "divide C_F by 1000" not in caplog.text


def test_a_robot_row_in_metres_is_named_where_the_data_put_it_1000_times_further():
    """A calibration engineer's trial: d_4 = -0.670 in a robot file in mm read only as 'd_4 moved -670 mm'."""
    from types import SimpleNamespace

    from rodlab.calibrate.trust import _metres_hint
    robot = SimpleNamespace(d_mm=np.array([0.0, 0.0, 0.0, -0.670]), a_mm=np.array([260.0, 680.0, -35.0, 0.0]))
    d4 = SimpleNamespace(kind="d", index=3, name="d_4")
    assert "d_4 = -0.67 looks like metres" in _metres_hint(robot, d4, -670.68) and "(-670)" in _metres_hint(robot, d4, -670.7)
    assert _metres_hint(robot, d4, -12.0) == ""                              # an error, not a unit
    assert _metres_hint(robot, SimpleNamespace(kind="a", index=1, name="a_2"), 695.0) == ""
