"""What a new user tripped over in session 41's trial: a built-in rod name where a compliance file is expected
(calibrate, simulate-campaign, diagnose --campaign), and a misleading fix for a column in the wrong unit."""
from __future__ import annotations

import pytest

from rodlab.app.cli.main import main


def test_a_builtin_rod_name_gives_its_closed_form_compliance_everywhere_a_compliance_file_goes(tmp_path, capsys):
    camp = tmp_path / "camp"
    assert main(["-q", "simulate-campaign", "--rod", "rod1",
                 "-o", str(camp)]) == 0
    assert main(["calibrate", str(camp / "multical.campaign.csv"), "--fixture", str(camp / "multical.fixture.json"),
                 "--rod", "1#", "--json", str(tmp_path / "cal.json")]) == 0
    assert "1#: the design's closed-form (calc) compliance" in capsys.readouterr().out


def test_a_rod_that_is_neither_a_file_nor_a_builtin_says_what_to_give(tmp_path, capsys):
    assert main(["simulate-campaign", "--rod", "rod9", "-o", str(tmp_path / "c")]) != 0
    err = capsys.readouterr().err
    assert "rod9: no such file, and not a built-in design" in err and "rodlab fea DESIGN -o FILE" in err
    assert "rod1" in err and not (tmp_path / "c").exists()


@pytest.mark.parametrize("word, choices, words", [
    ("disp_x_um", ["disp_x_mm", "mass_kg"], "multiply the values by 0.001"),
    ("mass_g", ["disp_x_mm", "mass_kg"], "multiply the values by 0.001"),
    ("wall_in", ["wall_mm", "outer_diameter_mm"], "multiply the values by 25.4"),
    ("force_kN", ["force_N"], "multiply the values by 1000"),
])
def test_a_name_in_another_unit_says_to_convert_as_well_as_rename(word, choices, words):
    from rodlab.core.errors import did_you_mean
    hint = did_you_mean(word, choices, units=True)
    assert "in another unit" in hint and words in hint and "a rename alone" in hint


@pytest.mark.parametrize("word, choices", [
    ("C_F_mm_per_kN", ["C_F_mm_per_N"]),           # a compound unit: the factor would be the inverse
    ("C_g", ["C_F"]),                              # g and F are not one kind of unit
    ("cte_ppm_C", ["cte_ppm_K"]),                  # temperatures: no hint
    ("upper_arm_lnk", ["upper_arm_link"]),         # not a unit at all
])
def test_no_unit_hint_where_a_factor_would_be_wrong(word, choices):
    from rodlab.core.errors import did_you_mean
    assert "in another unit" not in did_you_mean(word, choices, units=True)
    assert "in another unit" not in did_you_mean("disp_x_um", ["disp_x_mm"])   # only where the caller asks


def test_names_without_a_unit_slip_keep_their_suggestion():
    from rodlab.core.errors import did_you_mean
    assert did_you_mean("L1", ["L1_mm", "L2_mm"]) == " Did you mean `L1_mm`?"
    assert did_you_mean("dsip_x_mm", ["disp_x_mm"]) == " Did you mean `disp_x_mm`?"
    assert did_you_mean("zzz", ["disp_x_mm"]) == ""


@pytest.mark.parametrize("p, reduced, words", [(0.5, 1.0, "consistent with noise"),
                                               (0.0038, 1.57, "at the edge of the noise model"),
                                               (1e-5, 1.8, "slightly above noise"), (1e-9, 4.0, "NOT noise")])
def test_the_residual_verdict_never_calls_a_small_p_value_consistent(p, reduced, words):
    """A new user read "residuals consistent with noise ... (p = 0.0038)" as the result contradicting itself."""
    from rodlab.calibrate.residual_test import P_MISSING, ResidualTest
    t = ResidualTest(chi2=reduced * 50, dof=50, reduced=reduced, p_value=p, noise_mm=0.003,
                     fixture_sigma=(0.01, 0.002), missing=p < P_MISSING)
    assert t.wording.startswith(words)


def test_a_study_with_materials_on_a_grid_draws_the_best_design_per_cell(tmp_path):
    """--materials on an L1 x L2 grid: several designs per cell; the heat maps were silently left out."""
    import pandas as pd

    from rodlab.app.study.plots import plot_heatmaps
    rows = []
    for L1 in (250.0, 350.0):
        for L2 in (400.0, 500.0):
            for mat, err in (("steel", 0.05), ("cfrp", 0.03)):
                for method, f in (("none", 2.0), ("meas", 1.0)):
                    rows.append(dict(design=f"{mat} {L1:g}-{L2:g}", L1_mm=L1, L2_mm=L2, method=method,
                                     mean_mm=f * err * (1 + L1 / 1000)))
    png = plot_heatmaps(pd.DataFrame(rows), tmp_path / "heatmaps.png", "tx90")
    assert png is not None and png.stat().st_size > 10_000


def test_the_3d_views_of_rodlab_fea_go_into_the_png_folder(tmp_path):
    """`rodlab fea ... --png figs --fields steel.vtu --report` wrote steel.3d_F*.png beside the .vtu, not in figs/."""
    from argparse import Namespace
    from pathlib import Path

    from rodlab.app.cli.cmd_fea import _views_stem
    stem = Path("out") / "steel"
    assert _views_stem(Namespace(png=str(tmp_path / "figs")), stem) == tmp_path / "figs" / "steel"
    assert _views_stem(Namespace(png=str(tmp_path / "deformed.png")), stem) == stem   # one file: the views stay
    assert _views_stem(Namespace(png=None), stem) == stem


def test_validate_lists_a_campaign_in_radians_as_calibrate_refuses_it(tmp_path, capsys):
    """`rodlab validate` said "valid" of a campaign whose joint angles are radians; `calibrate` refuses it."""
    import csv
    import math
    camp = tmp_path / "camp"
    assert main(["-q", "simulate-campaign", "--rod", "rod1", "-o", str(camp)]) == 0
    rows = list(csv.reader((camp / "multical.campaign.csv").open()))
    rad = tmp_path / "rad.campaign.csv"
    with rad.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(rows[0])
        for r in rows[1:]:
            w.writerow([f"{math.radians(float(v)):.6f}" if rows[0][i].startswith("q") else v for i, v in enumerate(r)])
    capsys.readouterr()
    assert main(["validate", str(rad), str(camp / "multical.campaign.csv")]) == 2
    err = capsys.readouterr().err
    assert "look like radians" in err and "multiply them by 180/pi" in err and "1 of 2 file(s) not valid" in err


def test_a_folder_report_shows_fig8_with_the_fit_that_drew_it(tmp_path):
    """Two measured files in one folder, the second fitted with --png: its Fig. 8 was shown under the first."""
    import re as _re
    rec = tmp_path / "r.rig.csv"
    assert main(["-q", "rig", "simulate", "--sim", "rod1", "-o", str(rec)]) == 0
    assert main(["-q", "rig", "fit", str(rec), "--sim", "rod1", "-o", str(tmp_path / "a_first.compliance.json")]) == 0
    assert main(["-q", "rig", "fit", str(rec), "--sim", "rod1", "-o", str(tmp_path / "b_second.compliance.json"),
                 "--png", str(tmp_path)]) == 0
    out = tmp_path / "report.html"
    assert main(["-q", "report", str(tmp_path), "-o", str(out)]) == 0
    html = out.read_text()
    sections = _re.split(r"<h2>", html)
    first = next(s for s in sections if "a_first.compliance.json" in s)
    second = next(s for s in sections if "b_second.compliance.json" in s)
    assert "data:image/png;base64," not in first and "data:image/png;base64," in second
    assert "row x: (" in second                                   # r_mn rows no longer "x: - - 1.0031"


def test_tubes_are_drawn_in_their_material_s_colour():
    """A steel pipe I and an aluminium pipe II were drawn black like carbon in the CAD views."""
    from rodlab.core.design_io import resolve_design
    from rodlab.core.enums import Part
    from rodlab.geometry.parts import PART_COLOURS, part_colours
    carbon, steel = part_colours(resolve_design("rod1")), part_colours(resolve_design("rod4"))
    assert carbon[Part.PIPE_I] == PART_COLOURS[Part.PIPE_I] and max(carbon[Part.PIPE_I]) < 0.2   # carbon: dark
    assert min(steel[Part.PIPE_I]) > 0.4 and steel[Part.PIPE_I] == steel[Part.BEND]              # steel: metallic
    assert steel[Part.RING_1] == PART_COLOURS[Part.RING_1]                                         # sleeves keep theirs


def test_a_header_line_that_redefines_the_load_is_said_to_be_unread(tmp_path, caplog):
    """`# load_N: mass_lb * 4.448` was silently ignored; rodlab's own documenting line passes without a word."""
    import logging

    from rodlab.stiffness_rig import read_recording
    rec = tmp_path / "r.rig.csv"
    assert main(["-q", "rig", "simulate", "--sim", "rod1", "-o", str(rec)]) == 0
    with caplog.at_level(logging.WARNING):
        read_recording(rec)
    assert "is not read" not in caplog.text
    edited = tmp_path / "lb.rig.csv"
    edited.write_text("\n".join("# load_N: mass_lb * 4.448" if ln.startswith("# load_N:") else ln
                                for ln in rec.read_text().splitlines()) + "\n")
    with caplog.at_level(logging.WARNING):
        read_recording(edited)
    assert "'# load_N: mass_lb * 4.448' is not read" in caplog.text and "convert the values" in caplog.text


TWO_TOLERANCE_SLIPS = """format = "rodlab.rod/1"
name = "t"
L1_mm = 300.0
L2_mm = 450.0
gamma_deg = 90.0
[tube]
material = "cfrp"
outer_diameter_mm = 40.0
wall_mm = 5.0
[tolerances]
"tube.wal_mm" = 0.1
"L1_mm" = "8 percent"
"""


def test_every_problem_of_a_tolerance_table_at_once(tmp_path, capsys):
    """An unknown key and a malformed value: `validate` listed only the second (the schema's), `info` only the
    first (the reader's)."""
    from rodlab.core.design_io import load_design
    from rodlab.core.errors import DesignError
    path = tmp_path / "t.rod.toml"
    path.write_text(TWO_TOLERANCE_SLIPS)
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "2 problem(s)" in err and "unknown key 'tube.wal_mm'" in err and "'8 percent'" in err
    with pytest.raises(DesignError) as e:
        load_design(path)
    assert {x.key for x in (e.value, *e.value.also)} == {'tolerances."tube.wal_mm"', "tolerances.L1_mm"}
