"""What a new-user trial (2026-11-29, a calibration engineer at an integrator) found, fixed: a validation file with
its rod's mass in grams (a good calibration blamed for overfitting), a fixture file in metres, a compliance file's
centre of mass in metres, a campaign's rows copied under new point numbers (TRUSTED with shrunk uncertainties),
joint columns named J1..J6, a campaign exported with decimal commas (300 lines of errors), a campaign checked beside
another campaign's fixture by `validate`, `compare --rod none=none`, and another rod's compliance file whose
suspect line sent the user to the stiffness rig."""
from __future__ import annotations

import csv
import re
import json
from pathlib import Path

import pytest

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.cli.main import main
from rodlab.calibrate import read_campaign, read_fixture, read_points, resolve_robot
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.readings import point_unit_slips
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab.core.compliance import read_compliance, write_compliance
from rodlab.core.errors import did_you_mean

ROBOT = resolve_robot("tx90")
ROD = calc_rod_compliance(resolve_design("rod1"))


@pytest.fixture(scope="module")
def camp(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("camp46")
    simulate_campaign(ROBOT, ROD, out, CampaignSpec(seed=11))
    return out


def _rows(path: Path) -> tuple[list[str], list[list[str]]]:
    lines = [ln for ln in path.read_text().splitlines() if ln.strip()]
    rows = list(csv.reader(lines))
    return rows[0], rows[1:]


def _write(path: Path, header: list[str], rows: list[list[str]], quote: bool = False) -> Path:
    with open(path, "w", newline="") as f:
        csv.writer(f, quoting=csv.QUOTE_NONNUMERIC if quote else csv.QUOTE_MINIMAL).writerows([header, *rows])
    return path


def _edit_comment(src: Path, dst: Path, key: str, value: str) -> Path:
    dst.write_text("\n".join(f"# {key}: {value}" if ln.startswith(f"# {key}:") else ln
                             for ln in src.read_text().splitlines()) + "\n")
    return dst


def test_a_validation_rod_in_grams_or_metres_is_named_before_any_fit(camp, tmp_path, capsys):
    """`# rod_mass_kg: 300` (grams) had passed validate, and calibrate blamed its 6.3 mm validation error on
    overfitting; a tool vector in metres likewise: both named with the fix, the calibration refused before it runs."""
    grams = _edit_comment(camp / "multical.validation.csv", tmp_path / "g.validation.csv", "rod_mass_kg", "300")
    assert any("looks like grams" in s and "write 0.3" in s for s in point_unit_slips(read_points(grams), grams))
    metres = _edit_comment(camp / "multical.validation.csv", tmp_path / "m.validation.csv", "tool_mm", "0, 0, 0.15")
    assert any("looks like metres" in s for s in point_unit_slips(read_points(metres), metres))
    assert point_unit_slips(read_points(camp / "multical.validation.csv"), "v") == []
    assert main(["validate", str(grams)]) == 2
    code = main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
                 "--rod", str(next(camp.glob("*.compliance.json"))), "--validate", str(grams)])
    err = capsys.readouterr().err
    assert code == 2 and "rod_mass_kg is kilograms" in err and "overfitting" not in err


def test_a_fixture_in_metres_is_refused_by_its_reader(camp, tmp_path):
    data = json.loads((camp / "multical.fixture.json").read_text())
    data["positions"] = {k: [v / 1000 for v in p[:3]] + p[3:] for k, p in data["positions"].items()}
    path = tmp_path / "m.fixture.json"
    path.write_text(json.dumps(data))
    with pytest.raises(CalibrationError, match="look like metres") as e:
        read_fixture(path)
    assert e.value.key == "positions"
    read_fixture(camp / "multical.fixture.json")                         # the file as written passes
    same_place = dict(data, positions={"1": [122.466, 0.0, 86.607, 24.7, 24.5, -30.6],
                                       "5": [122.465, -0.01, 86.584, -12.2, -37.3, 24.8],
                                       "3": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0]}, world_position=3)
    (tmp_path / "s.fixture.json").write_text(json.dumps(same_place))     # two clampings at one place: not metres
    read_fixture(tmp_path / "s.fixture.json")


def test_a_centre_of_mass_in_metres_is_warned_of(tmp_path):
    rod = read_compliance(write_compliance(ROD, tmp_path / "r.compliance.json"))
    assert rod.unit_slips() == []
    data = json.loads((tmp_path / "r.compliance.json").read_text())
    data["com_T_mm"] = [v / 1000 for v in data["com_T_mm"]]
    (tmp_path / "m.compliance.json").write_text(json.dumps(data))
    slips = read_compliance(tmp_path / "m.compliance.json").unit_slips()
    assert len(slips) == 1 and "com_T_mm" in slips[0] and "multiply by 1000" in slips[0]
    data["com_T_mm"] = [8.5, 0.0, 0.0]                                    # near the ball, but not metres (8.5 m)
    (tmp_path / "n.compliance.json").write_text(json.dumps(data))
    assert read_compliance(tmp_path / "n.compliance.json").unit_slips() == []


def test_copied_rows_are_refused_and_repeats_are_not(camp, tmp_path, capsys):
    """Every row appended again as new points had been TRUSTED with its uncertainties shrunk by a factor 1.3: a copy
    (equal to below a micrometre) is refused naming both lines; a row repeated with its labels is told to be
    deleted, not renumbered; readings rounded to um that repeat a pose (a static repeat) stay."""
    header, rows = _rows(camp / "multical.campaign.csv")
    ip = header.index("point")
    copied = [r[:ip] + [str(int(r[ip]) + 100)] + r[ip + 1:] for r in rows[:3]]
    path = _write(tmp_path / "copy.campaign.csv", header, rows + copied)
    with pytest.raises(CalibrationError, match="repeats line 2 in every joint angle and reading") as e:
        read_campaign(path)
    assert "delete the copied rows" in str(e.value)
    assert main(["validate", str(path)]) == 2
    assert "delete the copied rows" in capsys.readouterr().err
    same = _write(tmp_path / "same.campaign.csv", header, rows + rows[:1])
    with pytest.raises(CalibrationError, match="the rows are the same: delete the repeated one"):
        read_campaign(same)
    ix = [header.index(c) for c in ("x_mm", "y_mm", "z_mm")]
    rounded = [[f"{float(c):.3f}" if i in ix else c for i, c in enumerate(r)] for r in rows]
    repeat = [rounded[0][:ip] + ["99"] + rounded[0][ip + 1:]]
    rep = _write(tmp_path / "rep.campaign.csv", header, rounded + repeat)
    assert len(read_campaign(rep).position) == len(rows) + 1
    assert main(["validate", str(rep)]) == 0                              # validate and the reader agree


def test_joint_columns_named_j1_are_told_to_be_q1(camp, tmp_path, capsys):
    header, rows = _rows(camp / "multical.campaign.csv")
    path = _write(tmp_path / "J.campaign.csv", [h.replace("q", "J") for h in header], rows)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err                       # six renames: one problem naming each (a trial)
    assert "the header names 6 columns otherwise" in err and "rename 'J1' to q1, 'J2' to q2" in err
    assert "Did you mean `q1`? (the joint angles are the columns q1" in did_you_mean("J1", ["q1", "x_mm"])
    assert "`q3`" in did_you_mean("A3", ["position", "q1", "x_mm"]) and "`q2`" in did_you_mean("joint_2", ["q1"])
    assert did_you_mean("J1", ["x_mm", "y_mm"]) == ""                   # no joint columns expected: no hint
    assert "q7" not in did_you_mean("J7", [f"q{k}" for k in range(1, 7)])  # no such joint: no such hint


def test_decimal_commas_are_one_problem_not_hundreds(camp, tmp_path, capsys):
    header, rows = _rows(camp / "multical.campaign.csv")
    commas = [[c.replace(".", ",") for c in r] for r in rows]
    path = _write(tmp_path / "c.campaign.csv", header, commas, quote=True)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("a decimal comma") == 2 and "more cells with a decimal comma" in err
    with pytest.raises(CalibrationError, match="a decimal comma .*export the file with a decimal point"):
        read_campaign(path)


def test_validate_pairs_a_campaign_with_its_fixture(camp, tmp_path, capsys):
    data = json.loads((camp / "multical.fixture.json").read_text())
    del data["positions"]["5"]
    short = tmp_path / "f4.fixture.json"
    short.write_text(json.dumps(data))
    assert main(["validate", str(camp / "multical.campaign.csv"), str(short)]) == 2
    assert "clamping position(s) [5] have no pose in" in capsys.readouterr().err
    assert main(["validate", str(camp / "multical.campaign.csv"), str(camp / "multical.fixture.json")]) == 0


def test_compare_with_none_as_a_file_says_none_is_always_run(camp, capsys):
    code = main(["compare", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
                 "--validate", str(camp / "multical.validation.csv"), "--rod", "none=none"])
    assert code == 2 and "compare runs the uncompensated calibration itself" in capsys.readouterr().err


def test_another_rods_file_is_named_in_the_suspect_line(camp, tmp_path, capsys):
    """Rod 3#'s file for rod 1#'s campaign: warned as another rod's, and the suspect rod_deflection no longer sends
    the user to the stiffness rig first."""
    other = write_compliance(calc_rod_compliance(resolve_design("rod3")), tmp_path / "rod3.compliance.json")
    code = main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
                 "--rod", str(other)])
    err = capsys.readouterr().err
    assert code == 3 and "is the rod file this rod's?" in err
    line = next((ln for ln in err.splitlines() if ln.strip().startswith("- rod_deflection")), "")
    assert "the rod file looks like another rod's" in line and "calibrate with this rod's compliance file" in line


def test_a_header_in_another_language_is_one_problem_with_every_rename(tmp_path, capsys):
    """German joint names and units in brackets (a trial: 13 problems, the expected list showing only q1)."""
    path = tmp_path / "de.validation.csv"
    path.write_text("# tool_mm: 0, 0, 109\nAchse1,Achse2,Achse3,Achse4,Achse5,Achse6,X [mm],Y [mm],Z [mm]\n"
                    "1,2,3,4,5,6,100,200,300\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "1 problem(s)" in err and "'Achse6' to q6" in err and "'X [mm]' to x_mm" in err


def test_diagnose_campaign_given_instrument_points_names_points(tmp_path, capsys):
    path = tmp_path / "p.validation.csv"
    path.write_text("# tool_mm: 0, 0, 109\nq1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm\n1,2,3,4,5,6,100,200,300\n")
    assert main(["diagnose", "--campaign", str(path)]) == 2
    assert f"diagnose it with --points {path}" in capsys.readouterr().err


def test_joints_counted_from_zero_are_renamed_one_up(tmp_path, capsys):
    """J0..J5 are q1..q6 (a review: J1 had been told to be q1, shifting every joint by one)."""
    path = tmp_path / "j0.validation.csv"
    path.write_text("# tool_mm: 0, 0, 109\nJ0,J1,J2,J3,J4,J5,x_mm,y_mm,z_mm\n1,2,3,4,5,6,100,200,300\n")
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "'J0' to q1" in err and "'J5' to q6" in err and "'J1' to q1" not in err


def test_compare_keeps_its_columns_under_a_long_label(camp, capsys):
    """A --rod label longer than the method column (a trial's `as-built-through-my-own-model`) had pushed its row's
    numbers out of line with the header's."""
    rod = str(camp / "rod1.compliance.json") if (camp / "rod1.compliance.json").exists() else \
        str(next(camp.glob("*.compliance.json")))
    main(["compare", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
          "--validate", str(camp / "multical.validation.csv"), "--rod", f"as-built-through-my-own-model={rod}"])
    rows = [ln for ln in capsys.readouterr().out.splitlines() if ln.split() and ln.split()[0] in
            ("method", "nominal", "None", "as-built-through-my-own-model")]
    assert len(rows) == 4
    ends = {re.match(r"\S+\s+\S+", ln).end() for ln in rows}        # where each row's first number ends
    assert len(ends) == 1, rows


def test_calibrate_writes_a_campaigns_residuals_with_their_labels(camp, tmp_path, capsys):
    out = tmp_path / "res.csv"
    main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
          "--rod", str(next(camp.glob("*.compliance.json"))), "--residuals", str(out)])
    rows = list(csv.DictReader(out.read_text().splitlines()))
    _, data = _rows(camp / "multical.campaign.csv")
    assert len(rows) == len(data) and rows[0]["label"].count(".") == 1
    assert f"wrote {out}" in capsys.readouterr().out


def test_a_soft_rod_rodlab_simulated_from_its_design_is_no_unit_slip(tmp_path):
    """C_F of 9 mm/N from rodlab's own simulation of a 3 m design is that design's (a designer trial had been told
    to divide it by 1000); the same numbers in a hand-made file still get the um/N hint."""
    from dataclasses import replace as dc_replace
    soft = read_compliance(write_compliance(dc_replace(ROD, C_F=ROD.C_F * 2000.0), tmp_path / "soft.compliance.json"))
    assert soft.simulated_by_rodlab and soft.unit_slips() == []
    hand = dc_replace(soft, provenance={})
    assert any("divide C_F by 1000" in s for s in hand.unit_slips())
    path = write_compliance(ROD, tmp_path / "r.compliance.json")          # rodlab's file, C_F scaled by hand
    data = json.loads(path.read_text())
    data["C_F_mm_per_N"] = [[1000 * v for v in row] for row in data["C_F_mm_per_N"]]
    (tmp_path / "e.compliance.json").write_text(json.dumps(data))
    edited = read_compliance(tmp_path / "e.compliance.json")
    assert not edited.simulated_by_rodlab and any("divide C_F by 1000" in s for s in edited.unit_slips())
    assert read_compliance(path).simulated_by_rodlab
