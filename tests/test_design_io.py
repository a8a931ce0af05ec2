"""Rod designs: the contract format, defaults, and every validation rule."""
from __future__ import annotations

from pathlib import Path

import math

import pytest

from rodlab import DesignError, FormatError, load_design, resolve_design
from rodlab.core.design_io import builtin_designs
from rodlab.core.enums import Part
from rodlab.core.massprops import part_mass_properties

from conftest import legacy_dict, write_toml


def test_builtins_load_and_match_paper_table2():
    names = builtin_designs()
    assert sorted(names) == [f"rod{i}" for i in range(1, 7)]
    lengths = {"rod1": (300, 450), "rod2": (150, 525), "rod3": (375, 600),
               "rod4": (300, 450), "rod5": (150, 525), "rod6": (375, 600)}
    for key, (l1, l2) in lengths.items():
        d = resolve_design(key)
        assert (d.L1_mm, d.L2_mm, d.gamma_deg) == (l1, l2, 90.0)
    assert resolve_design("1#").name == "1#"


def test_shared_examples_load(examples):
    for f in sorted((examples / "rods").glob("*.rod.toml")):
        d = load_design(f)
        assert d.tool_mm[0] == pytest.approx(d.L2_mm)


def test_tool_point_eq1(tmp_path, rod1_dict):
    rod1_dict["gamma_deg"] = 120.0
    d = load_design(write_toml(tmp_path / "r.rod.toml", rod1_dict))
    g = math.radians(120)
    assert d.tool_mm == pytest.approx([450 * math.sin(g), 0.0, 300 - 450 * math.cos(g)])


def test_defaults_and_absent_parts(tmp_path):
    data = {"format": "rodlab.rod/1", "name": "min", "L1_mm": 300.0, "L2_mm": 400.0, "gamma_deg": 90.0,
            "tube": {"material": "cfrp", "outer_diameter_mm": 20.0, "wall_mm": 1.5}}
    d = load_design(write_toml(tmp_path / "m.rod.toml", data))
    assert d.bend.material.name == "cfrp" and d.bend.radius_mm == 40.0   # tube itself, bent, R = 2 OD
    assert d.ball.material.name == "alumina" and d.ball.diameter_mm == 30.0
    assert d.rings.present and d.pipe_holder.present and d.ball_holder.present
    data["rings"] = {"length_mm": 0.0}
    data["pipe_holder"] = {"length_mm": 0}
    data["ball_holder"] = {"length_mm": 0}
    d = load_design(write_toml(tmp_path / "m2.rod.toml", data))
    parts = set(part_mass_properties(d))
    assert parts == {Part.PIPE_I, Part.BEND, Part.PIPE_II, Part.BALL}


def test_pipe_override_and_bend_only_radius(tmp_path, rod1_dict):
    rod1_dict["pipe_II"] = {"outer_diameter_mm": 22.0}
    rod1_dict["bend"] = {"radius_mm": 50.0}
    d = load_design(write_toml(tmp_path / "o.rod.toml", rod1_dict))
    assert d.pipe_II.outer_diameter_mm == 22.0 and d.pipe_II.wall_mm == 2.0
    assert d.pipe_I.outer_diameter_mm == 25.0
    assert d.bend.material.name == "cfrp_tube" and d.bend.outer_diameter_mm == 25.0 and d.bend.radius_mm == 50


def test_user_material_is_transversely_isotropic(rod1_dict, tmp_path):
    d = load_design(write_toml(tmp_path / "u.rod.toml", rod1_dict))
    m = d.pipe_I.material
    assert m.name == "cfrp_tube" and not m.is_isotropic and m.G_axial_GPa == 10.0 and m.E_t_GPa == 100.0


# --- every validation rule: (mutation, expected key, words in the message) -------------------
def _set(path, value):
    def f(d):
        node = d
        for k in path[:-1]:
            node = node.setdefault(k, {})
        node[path[-1]] = value
    return f


RULES = [
    ("wall >= radius", _set(("tube", "wall_mm"), 12.5), "tube.wall_mm", "outer radius"),
    ("ring too narrow", _set(("rings", "outer_diameter_mm"), 25.0), "rings.outer_diameter_mm", "do not fit"),
    ("holder too narrow", _set(("pipe_holder", "outer_diameter_mm"), 24.0), "pipe_holder.outer_diameter_mm",
     "does not fit"),
    ("stud wider than ball", _set(("ball_holder", "outer_diameter_mm"), 31.0), "ball_holder.outer_diameter_mm",
     "narrower"),
    ("bend radius", _set(("bend", "radius_mm"), 30.0), "bend.radius_mm", "1.5"),
    ("L1 too short", _set(("L1_mm",), 100.0), "L1_mm", "too short"),
    ("L2 too short", _set(("L2_mm",), 120.0), "L2_mm", "too short"),
    ("unknown material", _set(("tube", "material"), "steel_340"), "tube.material", "steel_304"),
    ("unknown key", _set(("tube", "wall"), 2.0), "tube.wall", "wall_mm"),
    ("unknown top key", _set(("L3_mm",), 2.0), "L3_mm", "allowed"),
    ("negative", _set(("tube", "outer_diameter_mm"), -25.0), "tube.outer_diameter_mm", "non-negative"),
    ("zero diameter", _set(("ball", "diameter_mm"), 0.0), "ball.diameter_mm", "> 0"),
    ("nan", _set(("L2_mm",), float("nan")), "L2_mm", "finite"),
    ("inf", _set(("rings", "length_mm"), float("inf")), "rings.length_mm", "finite"),
    ("string number", _set(("L1_mm",), "300"), "L1_mm", "number"),
    ("gamma 0", _set(("gamma_deg",), 0.0), "gamma_deg", "(0, 180]"),
    ("gamma 190", _set(("gamma_deg",), 190.0), "gamma_deg", "(0, 180]"),
    ("format", _set(("format",), "rodlab.rod/3"), "format", "rodlab.rod/1"),
    ("material E", _set(("materials", "cfrp_tube", "E_GPa"), -1.0), "materials.cfrp_tube.E_GPa", ""),
    ("material nu", _set(("materials", "cfrp_tube", "nu"), 0.7), "materials.cfrp_tube.nu", "nu"),
    ("material key", _set(("materials", "cfrp_tube", "density"), 1.0), "materials.cfrp_tube.density",
     "density_kg_m3"),
    ("bare L1 key", _set(("L1",), 300.0), "L1", "Did you mean `L1_mm`"),
    ("hangs rather than reaches", _set(("L2_mm",), 9000.0), "L2_mm", "hang rather than reach"),
    # units slips: named as such, not as a geometry rule they break further on
    ("modulus in Pa", _set(("materials", "cfrp_tube", "E_GPa"), 140e9), "materials.cfrp_tube.E_GPa", "= 140 GPa"),
    ("modulus in MPa", _set(("materials", "cfrp_tube", "G_GPa"), 10000.0), "materials.cfrp_tube.G_GPa", "MPa"),
    ("modulus far too low", _set(("materials", "cfrp_tube", "E_GPa"), 0.001), "materials.cfrp_tube.E_GPa",
     "rubber"),
    ("density in g/cm3", _set(("materials", "cfrp_tube", "density_kg_m3"), 1.58),
     "materials.cfrp_tube.density_kg_m3", "1580 kg/m^3"),
    ("gamma in radians", _set(("gamma_deg",), 1.9), "gamma_deg", "did you give radians"),
    ("absurd size", _set(("tube", "outer_diameter_mm"), 1e300), "tube.outer_diameter_mm", "<= 10000 mm"),
    ("length in um", _set(("L1_mm",), 300000.0), "L1_mm", "millimetres"),
    ("diameter in metres", _set(("tube", "outer_diameter_mm"), 0.04), "tube.outer_diameter_mm", "did you give metres"),
    # a designer trial: OD and wall both in metres had been a tube sagging 9e10 mm, blamed on L2
    ("diameter and wall in metres", lambda d: (_set(("tube", "outer_diameter_mm"), 0.04)(d),
                                               _set(("tube", "wall_mm"), 0.005)(d)),
     "tube.outer_diameter_mm", "0.005 m = 5 mm"),
    ("wall in metres", _set(("tube", "wall_mm"), 0.005), "tube.wall_mm", "did you give metres (0.005 m = 5 mm)"),
    # a review: a wall of 0.03 on a 40 mm tube read as metres is 30 mm, no tube: a typo, not metres
    ("wall mistyped", _set(("tube", "wall_mm"), 0.03), "tube.wall_mm", "check the value"),
    # a designer trial: an OD of 1.575 (inches) had been blamed on the wall; a tube in cm on L2 alone
    ("diameter in inches", _set(("tube", "outer_diameter_mm"), 1.575), "tube.outer_diameter_mm", "in inches (1.575 x 25.4"),
    ("tube in centimetres", lambda d: (_set(("tube", "outer_diameter_mm"), 4.0)(d), _set(("tube", "wall_mm"), 0.3)(d),
                                       d.pop("bend", None)),
     "tube.outer_diameter_mm", "given in centimetres (4 x 10 = 40 mm, wall 3 mm) or inches"),
    # a designer trial: lengths in inches had read "L1 too short" alone
    ("lengths in inches", lambda d: (d.update(L1_mm=15.75, L2_mm=23.6)), "L1_mm", "did you give inches (15.75 in = 400"),
]


@pytest.mark.parametrize("label,mutate,key,words", RULES, ids=[r[0] for r in RULES])
def test_validation_rule(tmp_path, rod1_dict, label, mutate, key, words):
    mutate(rod1_dict)
    path = write_toml(tmp_path / "bad.rod.toml", rod1_dict)
    with pytest.raises(FormatError) as ei:
        load_design(path)
    err = ei.value
    assert err.key == key, str(err)
    assert str(path) in str(err)
    assert words in str(err)
    if key.split(".")[-1] in path.read_text():
        assert err.line is not None, str(err)
        line = path.read_text().splitlines()[err.line - 1]
        assert key.split(".")[-1] in line or line.startswith("["), (err.line, line)


def test_every_broken_rule_is_reported_at_once_with_its_line(tmp_path, rod1_dict):
    """Three rules broken at once (bend radius, L1 and L2 too short): the error leads with the first and carries
    the others, each with its own key and line; ``rodlab validate`` lists all three."""
    from rodlab.app.cli.cmd_validate import validate_file
    _set(("bend", "radius_mm"), 0.9 * rod1_dict["bend"]["outer_diameter_mm"])(rod1_dict)
    _set(("L1_mm",), 60.0)(rod1_dict)
    _set(("L2_mm",), 50.0)(rod1_dict)
    path = write_toml(tmp_path / "bad.rod.toml", rod1_dict)
    with pytest.raises(DesignError) as ei:
        load_design(path)
    keys = [e.key for e in (ei.value, *ei.value.also)]
    assert keys == ["bend.radius_mm", "L1_mm", "L2_mm"]
    lines = path.read_text().splitlines()
    for e in (ei.value, *ei.value.also):
        assert e.path == str(path) and e.key.split(".")[-1] in lines[e.line - 1]
    assert str(ei.value).count("too short") == 2          # the CLI's message shows every problem
    check = validate_file(path)
    assert [p.key for p in check.problems] == keys


def test_every_broken_part_is_reported_at_once(tmp_path, rod1_dict):
    """Two parts broken (the tubes' wall, the bend's own wall): both named; a units slip still names one cause."""
    _set(("tube", "wall_mm"), 0.6 * rod1_dict["tube"]["outer_diameter_mm"])(rod1_dict)
    rod1_dict["bend"].update(material="steel_304", outer_diameter_mm=40.0, wall_mm=30.0)
    path = write_toml(tmp_path / "bad.rod.toml", rod1_dict)
    with pytest.raises(DesignError) as ei:
        load_design(path)
    assert [e.key for e in (ei.value, *ei.value.also)] == ["tube.wall_mm", "bend.wall_mm"]


def test_range_warnings_name_key_range_and_line(tmp_path, rod1_dict, caplog):
    """Inside the checked range a design loads silently; outside it, a warning per key with the range and the
    file's line; a long rod also gets the linear model's second-order error (sag^2 / reach)."""
    import logging

    from rodlab.core.design_range import VERIFIED_RANGE, linear_model_error_mm, range_warnings
    with caplog.at_level(logging.WARNING, logger="rodlab.core.design_io"):
        load_design(write_toml(tmp_path / "ok.rod.toml", rod1_dict))
    assert not caplog.records
    rod1_dict["L2_mm"] = 4500.0
    path = write_toml(tmp_path / "long.rod.toml", rod1_dict)
    with caplog.at_level(logging.WARNING, logger="rodlab.core.design_io"):
        d = load_design(path)
    text = caplog.text
    line = next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if ln.startswith("L2_mm"))
    lo, hi, _ = VERIFIED_RANGE["L2_mm"]
    assert f"{path}, line {line}, key `L2_mm` = 4500 mm lies outside {lo:g}-{hi:g} mm" in text
    sag, err = linear_model_error_mm(d)
    assert err == pytest.approx(sag ** 2 / float((d.tool_mm ** 2).sum()) ** 0.5)
    assert 100.0 < sag < 1000.0 and "sags" in text          # a 4.5 m carbon tube sags by decimetres
    assert [w.key for w in range_warnings(d)] == ["L2_mm", "L2_mm"]
    rod1_dict["L2_mm"], rod1_dict["gamma_deg"] = 300.0, 40.0      # ball in front of the flange, sharp bend
    assert [w.key for w in range_warnings(load_design(write_toml(tmp_path / "g.rod.toml", rod1_dict)))] == [
        "gamma_deg"]
    rod1_dict["L2_mm"], rod1_dict["gamma_deg"] = 450.0, 30.0      # ball 89.7 mm behind the flange plane
    warnings = range_warnings(load_design(write_toml(tmp_path / "b.rod.toml", rod1_dict)))
    assert [w.key for w in warnings] == ["gamma_deg", "gamma_deg"]
    assert "89.7 mm behind the flange plane" in warnings[1].describe()


def test_missing_required_and_toml_syntax(tmp_path, rod1_dict):
    del rod1_dict["L2_mm"]
    with pytest.raises(DesignError, match="L2_mm"):
        load_design(write_toml(tmp_path / "a.rod.toml", rod1_dict))
    p = tmp_path / "b.rod.toml"
    p.write_text('format = "rodlab.rod/1"\nL1_mm = = 3\n')
    with pytest.raises(FormatError) as ei:
        load_design(p)
    assert ei.value.line == 2 and "TOML" in str(ei.value)
    with pytest.raises(FormatError, match="not found"):
        load_design(tmp_path / "nope.rod.toml")
    q = tmp_path / "c.rod.toml"
    q.write_bytes(b"\xff\xfe\x00junk")
    with pytest.raises(FormatError, match="UTF-8"):
        load_design(q)


def test_design_to_dict_round_trip():
    """Every built-in design written as a rodlab.rod/1 table (parts and material numbers explicit) reads back
    equal, also with a part removed and a user material."""
    from dataclasses import replace

    from rodlab.core.design_io import design_from_dict, design_to_dict
    from rodlab.core.materials import Material
    designs = [resolve_design(n) for n in builtin_designs()]
    d = designs[0]
    designs.append(replace(d, rings=replace(d.rings, length_mm=0.0),
                           bend=replace(d.bend, material=Material("ti_mine", 110.0, 0.33, 4430.0))))
    for d in designs:
        t = design_to_dict(d)
        assert t["format"] == "rodlab.rod/1" and d.bend.material.name in t["materials"]
        assert design_from_dict(t) == d


def test_the_built_in_designs_pass_the_schema_they_are_loaded_without():
    """resolve_design skips the JSON Schema pass for the built-ins (start-up time): they must pass it."""
    from rodlab.core.schema import check_file
    for name, path in builtin_designs().items():
        check = check_file(path)
        assert not check.problems, (name, check.problems)
        assert load_design(path) == resolve_design(name)


def test_every_unknown_key_of_a_table_is_one_problem(tmp_path):
    """`wal_mm` and `radius` in one [bend] table: both named at once, each with its line and suggestion (a designer
    trial: the second had shown only after the first was fixed)."""
    from rodlab.core.schema import check_file
    text = Path(builtin_designs()["rod1"]).read_text()
    assert "[bend]" in text and "radius_mm =" in text
    text = text.replace("radius_mm =", "radius =", 1).replace("[bend]", "[bend]\nwal_mm = 2.0", 1)
    path = tmp_path / "typo.rod.toml"
    path.write_text(text)
    keys = {p.key: p for p in check_file(path).problems}
    assert {"bend.wal_mm", "bend.radius"} <= set(keys)
    assert "wall_mm" in keys["bend.wal_mm"].fix and "radius_mm" in keys["bend.radius"].fix
    assert keys["bend.radius"].line == text.splitlines().index(next(s for s in text.splitlines()
                                                                    if s.startswith("radius ="))) + 1


def test_the_sag_warning_is_not_a_range_warning_and_a_hopeless_sag_says_so():
    """A 3-6 m rod: its sag warning names the key and value, not "lies outside 250-2000 mm" (that is the other
    warning's), and where the linear models are off by more than 1 mm it says no compensation helps."""
    from dataclasses import replace

    from rodlab.core.design_range import range_warnings
    long = replace(resolve_design("rod1"), L2_mm=6000.0)
    texts = [w.describe() for w in range_warnings(long)]
    sag = next(t for t in texts if "sags" in t)
    assert sag.startswith("key `L2_mm` = 6000 mm: the rod sags") and "no linear compliance model brings" in sag
    assert any("lies outside 250-2000 mm" in t and "sags" not in t for t in texts)


def test_a_carbon_tube_without_a_bend_table_is_warned_of(tmp_path, rod1_dict, caplog):
    """A designer trial: a carbon rod without [bend] was valid without a word, its bend a pultruded tube bent to
    80 mm, which cannot be made; a steel [bend] gives no warning."""
    import logging
    tube = rod1_dict["tube"]
    rod1_dict["bend"] = {"material": "steel_304", "outer_diameter_mm": tube["outer_diameter_mm"],
                         "wall_mm": tube["wall_mm"], "radius_mm": 2.6 * tube["outer_diameter_mm"]}
    with caplog.at_level(logging.WARNING, logger="rodlab"):
        load_design(write_toml(tmp_path / "steel_bend.rod.toml", rod1_dict))
    assert "no [bend] material" not in caplog.text
    del rod1_dict["bend"]
    with caplog.at_level(logging.WARNING, logger="rodlab"):
        load_design(write_toml(tmp_path / "no_bend.rod.toml", rod1_dict))
    assert "no [bend] material" in caplog.text and "cannot be" in caplog.text


def test_a_foil_thin_wall_is_warned_of_on_its_line(tmp_path, rod1_dict, caplog):
    """A new-user trial: a 0.05 mm wall on a 30 mm tube (D/t 600) passed with a sag warning pinned to L2 alone."""
    import logging
    rod1_dict["tube"]["wall_mm"] = 0.05
    rod1_dict["tube"]["outer_diameter_mm"] = 30.0
    rod1_dict.pop("bend", None)
    path = write_toml(tmp_path / "foil.rod.toml", rod1_dict)
    with caplog.at_level(logging.WARNING):
        load_design(path)
    said = [r.getMessage() for r in caplog.records if "is a foil" in r.getMessage()]
    assert len(said) == 1 and "key `tube.wall_mm`" in said[0] and "D/t 600" in said[0] and ", line " in said[0]
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        load_design(write_toml(tmp_path / "rod1.rod.toml", legacy_dict("rod1")))
    assert not [r for r in caplog.records if "is a foil" in r.getMessage()]
