"""The shipped schemas of rodlab's file formats and `rodlab validate`: every file rodlab ships or writes passes
its schema and its reader; a broken file is refused by both, with every problem listed at once."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from rodlab.app.cli.cmd_validate import READERS, validate_file
from rodlab.app.cli.main import main
from rodlab.core.schema import FORMATS, check_file, load_schema

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = sorted([*ROOT.glob("rodlab/data/**/*.toml"), *ROOT.glob("calibrate/robots/*.toml"),
                  *ROOT.glob("stiffness_rig/plans/*.toml"), *ROOT.glob("calibrate/robots/*.urdf"),
                  *ROOT.glob("benchmarks/data/*/*.csv"), *ROOT.glob("*/blind_cases.toml")])


def test_schemas_are_valid_json_schemas_and_cover_every_format():
    from jsonschema import Draft202012Validator
    for fid, spec in FORMATS.items():
        schema = load_schema(fid)
        assert schema["$id"] == fid
        if spec.kind != "csv":
            Draft202012Validator.check_schema(schema)
        assert fid in READERS
    doc = (ROOT / "docs" / "formats.md").read_text()
    assert all(fid in doc for fid in FORMATS), [f for f in FORMATS if f not in doc]


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_every_shipped_file_is_valid(path):
    check = validate_file(path)
    assert check.ok and check.format is not None, [str(p) for p in check.problems]


def test_files_rodlab_writes_are_valid(tmp_path, examples):
    data = ROOT / "benchmarks" / "data" / "landgraf2021" / "ur10_D.validation.csv"
    cal, diag = tmp_path / "cal.json", tmp_path / "d.json"
    main(["calibrate", "--points", str(data), "--robot", "ur10", "--fix-unidentifiable", "--json", str(cal)])
    main(["diagnose", "--points", str(data), "--robot", "ur10", "--json", str(diag)])
    written = [cal, diag, *sorted(p for p in examples.rglob("*") if p.is_file() and "truth" not in p.name
                                  and p.suffix in (".csv", ".json", ".toml"))]
    for p in written:
        check = validate_file(p)
        assert check.ok and check.format, (p, [str(x) for x in check.problems])


def _mutations(examples):
    comp = json.loads((examples / "rod1.compliance.json").read_text())
    fix = json.loads(next(examples.rglob("*.fixture.json")).read_text())
    rod = (ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml").read_text()
    plan = (ROOT / "stiffness_rig" / "plans" / "quick.plan.toml").read_text()
    camp = next(examples.rglob("*.campaign.csv")).read_text().splitlines()
    prof = (ROOT / "stiffness_rig" / "plans" / "simulator.profile.toml").read_text()
    return {
        "n.profile.toml": prof.replace("index = 1", "index = -1", 1),
        "c.compliance.json": json.dumps({**comp, "method": "fem"}),
        "d.compliance.json": json.dumps({**comp, "tool_mm": [1, 2]}),
        "e.compliance.json": json.dumps({k: v for k, v in comp.items() if k != "mass_kg"}),
        "f.fixture.json": json.dumps({**fix, "positions": {"1": [0, 0, 0, 0, 0]}, "world_position": 1}),
        "g.fixture.json": json.dumps({**fix, "contact_force_N": [1, 2]}),
        "r.rod.toml": rod.replace("L1_mm", "L1"),
        "s.rod.toml": rod.replace("[ball]", "[ball]\ncolour = 1"),
        "p.plan.toml": plan.replace('axes = ["y", "z"]', 'axes = ["y", "w"]'),
        "q.plan.toml": plan.replace("repeats = 2", "repeats = 2.5"),
        "a.campaign.csv": "\n".join(camp[:3] + [camp[3].replace(",", ",x", 1)] + camp[4:]),
        "b.campaign.csv": "\n".join([camp[0].replace("x_mm", "x")] + camp[1:]),
    }


def test_schema_and_reader_agree_on_broken_files(tmp_path, examples):
    """Each broken file is refused by its schema and, checked alone, by its reader: the schema is the reader's
    contract, not a second opinion."""
    for name, text in _mutations(examples).items():
        p = tmp_path / name
        p.write_text(text)
        check = check_file(p)
        assert not check.ok, name
        with pytest.raises(ValueError):
            READERS[check.format](p)


def test_validate_lists_every_problem_with_line_key_and_fix(tmp_path, capsys, examples):
    bad = tmp_path / "bad.campaign.csv"
    camp = next(examples.rglob("*.campaign.csv")).read_text().splitlines()
    rows = camp[1:6]
    rows[1] = rows[1].replace(rows[1].split(",")[3], "abc", 1)
    rows[3] = ",".join(rows[3].split(",")[:-2])
    bad.write_text("\n".join([camp[0] + ",temp"] + [r + ",20" for r in rows]) + "\n")
    good = ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml"
    assert main(["validate", str(good), str(bad)]) == 2
    out = capsys.readouterr()
    assert f"{good}: rodlab.rod/1, valid" in out.out
    err = out.err
    assert "bad.campaign.csv: rodlab.campaign/1, 3 problem(s)" in err
    assert "line 1, key `temp`: unknown column" in err and "Did you mean `temp_C`?" in err
    assert "line 3, key `q2`: expected a number, got 'abc'" in err and "line 5: expected" in err
    assert main(["validate", str(good)]) == 0


def test_validate_names_unknown_formats_and_missing_files(tmp_path, capsys):
    p = tmp_path / "x.json"
    p.write_text('{"format": "rodlab.compliance/3"}')
    assert main(["validate", str(p), str(tmp_path / "none.rod.toml")]) == 2
    err = capsys.readouterr().err
    assert "unknown format 'rodlab.compliance/3'" in err and "Did you mean `rodlab.compliance/" in err
    assert "none.rod.toml: file not found" in err


def test_reader_rules_beyond_the_schema_are_reported(tmp_path, capsys):
    """A plan whose masses repeat passes the schema (no JSON Schema rule says "increasing") but not its reader:
    validate reports the reader's problem with its line."""
    plan = (ROOT / "stiffness_rig" / "plans" / "quick.plan.toml").read_text()
    p = tmp_path / "same.plan.toml"
    p.write_text(plan.replace("masses_kg = [0.5, 1.0]", "masses_kg = [1.0, 1.0]"))
    assert check_file(p).ok
    check = validate_file(p)
    assert not check.ok and check.problems[0].key == "masses_kg" and "strictly" in check.problems[0].message
    assert check.problems[0].line == plan.splitlines().index("masses_kg = [0.5, 1.0]") + 1


def test_output_records_without_a_schema_are_named_not_refused(tmp_path, capsys):
    p = tmp_path / "run.json"
    p.write_text('{"format": "rodlab.run/1", "steps": []}')
    assert main(["validate", str(p)]) == 0
    assert "rodlab.run/1, valid (an output record of rodlab without a schema" in capsys.readouterr().out
    p.write_text('{"format": "rodlab.run/1", "steps": [}')
    assert main(["validate", str(p)]) == 2
    assert "not valid JSON" in capsys.readouterr().err


@pytest.mark.parametrize("masses", ["[0.5, inf]", "[nan, 1.0]"])
def test_plan_refuses_infinite_or_nan_masses_naming_file_and_key(tmp_path, masses):
    """Found by the reader fuzzing: an infinite mass passed the plan reader and failed later without the file."""
    from rodlab.stiffness_rig.config import read_plan
    from rodlab.stiffness_rig.errors import RigError
    plan = (ROOT / "stiffness_rig" / "plans" / "quick.plan.toml").read_text()
    p = tmp_path / "m.plan.toml"
    p.write_text(plan.replace("masses_kg = [0.5, 1.0]", f"masses_kg = {masses}"))
    with pytest.raises(RigError) as e:
        read_plan(p)
    assert e.value.key == "masses_kg" and "m.plan.toml" in str(e.value) and "finite" in str(e.value)


def test_a_problem_in_a_later_instrument_is_named_at_its_own_line(tmp_path, capsys):
    """The line of `instrument[2].channel[1].units` is the second instrument's channel's, not the first `units` in
    the file (new-user trial: line 17 for a key on line 31)."""
    from rodlab.stiffness_rig.config import _line
    text = (ROOT / "stiffness_rig" / "plans" / "two-digimatic.profile.toml").read_text()
    lines = text.splitlines()
    second = [i for i, s in enumerate(lines) if s.strip().startswith("[[instrument]]")][1]
    units = next(i for i in range(second, len(lines)) if lines[i].strip().startswith("units"))
    lines[units] = 'units = "inch"'
    bad = tmp_path / "p.profile.toml"
    bad.write_text("\n".join(lines) + "\n")
    assert main(["validate", str(bad)]) == 2
    assert f"line {units + 1}, key `instrument[2].channel[1].units`" in capsys.readouterr().err
    assert _line(bad.read_text(), "instrument[2].channel[1].units") == units + 1


def _scaled_rig(src: Path, dst: Path, factor: float) -> None:
    lines, out, header = src.read_text().splitlines(), [], None
    for line in lines:
        if line.startswith("#") or header is None:
            header = header if line.startswith("#") else line.split(",")
            out.append(line)
            continue
        cells = line.split(",")
        for i, h in enumerate(header):
            if h.startswith("disp_") and cells[i]:
                cells[i] = f"{float(cells[i]) * factor:.6g}"
        out.append(",".join(cells))
    dst.write_text("\n".join(out) + "\n")


@pytest.mark.parametrize("factor, words", [(1000.0, "if disp_mm is in um, divide it by 1000"),
                                           (0.001, "a displacement in metres")])
def test_a_recording_or_compliance_file_in_other_units_is_valid_with_its_warning(tmp_path, capsys, factor, words):
    """A new user's recording in um (or metres) and a compliance file in um/N pass their schema: `validate` says
    so and lists the unit slips the readers find under the file, not only as log lines (new-user trial)."""
    from rodlab.core.compliance import write_compliance
    assert main(["rig", "simulate", "--sim", "rod1", "--repeats", "1", "--hold-s", "4", "-o",
                 str(tmp_path / "ok.rig.csv")]) == 0
    _scaled_rig(tmp_path / "ok.rig.csv", tmp_path / "slip.rig.csv", factor)
    capsys.readouterr()
    assert main(["validate", str(tmp_path / "ok.rig.csv"), str(tmp_path / "slip.rig.csv")]) == 0
    out = capsys.readouterr().out
    assert "ok.rig.csv: rodlab.rig/1, valid\n" in out and "slip.rig.csv: rodlab.rig/1, valid, but with" in out
    assert words in out
    from dataclasses import replace
    from rodlab import calc_rod_compliance, resolve_design
    rod = calc_rod_compliance(resolve_design("rod1"))
    # a user's file in um/N (not rodlab's simulation of a design, whose numbers are the design's however soft)
    write_compliance(replace(rod, C_F=rod.C_F * 1000.0, provenance={"generator": "my FEA"}),
                     tmp_path / "um.compliance.json")
    assert main(["validate", str(tmp_path / "um.compliance.json")]) == 0
    assert "if the file is in um/N, divide C_F by 1000" in capsys.readouterr().out


def test_a_key_or_table_given_twice_is_named(tmp_path, capsys):
    """The TOML parser says only "Cannot overwrite a value": the key (or table) and its line are named (an
    instrument trial's profile with a copied baudrate line)."""
    from rodlab.app.cli.main import main
    prof = tmp_path / "dup.profile.toml"
    prof.write_text('format = "rodlab.rigprofile/2"\n[[instrument]]\nname = "g"\nport = "/dev/null"\n'
                    'baudrate = 9600\nbaudrate = 19200  # the new gauge\n')
    rod = tmp_path / "dup.rod.toml"
    rod.write_text('name = "x"\n[tube]\nouter_diameter_mm = 40\n\n[tube]\nwall_mm = 5\n')
    assert main(["validate", str(prof), str(rod)]) != 0
    cap = capsys.readouterr()
    out = cap.out + cap.err
    assert "line 6" in out and "'baudrate' is given a second time in its table at line 6; keep one" in out
    assert "the table [tube] is declared a second time at line 5; merge the two" in out


def test_a_key_repeated_in_every_element_of_a_json_array_is_located_in_its_own_element(tmp_path, capsys):
    """A device file (v1) with reading_sign in each of its three sensors: each problem at its own line (a device
    trial: all three had been put at the first one's line)."""
    import json as _json

    from rodlab.app.cli.main import main
    sensor = {"axis_D": [1, 0, 0], "zero_mm": 5.0, "range_mm": [0, 10], "rate_N_per_mm": 0.1,
              "force_at_zero_N": 1.0, "reading_sign": 1}
    text = _json.dumps({"format": "rodlab.device/1", "sensors": [sensor, sensor, sensor]}, indent=1)
    path = tmp_path / "d.device.json"
    path.write_text(text)
    main(["validate", str(path)])
    out = capsys.readouterr()
    lines = [i + 1 for i, ln in enumerate(text.splitlines()) if "reading_sign" in ln]
    for k, line in enumerate(lines, 1):
        assert f"line {line}, key `sensors[{k}].reading_sign`" in out.out + out.err
