"""A lab technician's trial (2026-11-29, helper-52): an interrupted run's unmeasured entry, a truncated last line,
the diagnosis's export of a joint it could not place to one part, a gauge reversed in one series."""
from __future__ import annotations

import json

import pytest

from rodlab.app.cli import main


def _edit_rows(rec, edit) -> None:
    """Rewrite a recording's data rows in place: ``edit(header cells, row cells)`` changes the row's cells."""
    lines = rec.read_text().splitlines()
    header = next(i for i, ln in enumerate(lines) if ln.startswith("time_s"))
    cols = lines[header].split(",")
    for i in range(header + 1, len(lines)):
        if lines[i].startswith("#"):
            continue
        cells = lines[i].split(",")
        edit(cols, cells)
        lines[i] = ",".join(cells)
    rec.write_text("\n".join(lines) + "\n")


def _interrupted(tmp_path, capsys):
    """A recording without the x series (the run stopped before it) and its measured file."""
    sim, rec, meas = tmp_path / "rod1.calc.json", tmp_path / "yz.rig.csv", tmp_path / "yz.meas.json"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--axes", "y,z", "--effect", "compliance_scale:r=1.3",
                 "--repeats", "2", "--hold-s", "4", "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["rig", "fit", str(rec), "--sim", str(sim), "-o", str(meas)]) == 0
    return rec, meas, capsys.readouterr().out


def test_an_unmeasured_entry_is_said_and_left_out_of_update(tmp_path, capsys):
    rec, meas, fit_out = _interrupted(tmp_path, capsys)
    assert "not measured: c11" in fit_out
    assert json.loads(meas.read_text())["C_F_sigma_mm_per_N"][0][0] is None
    out = tmp_path / "asbuilt.rod.toml"
    assert main(["update", "rod1", "--measured", str(meas), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "c11 not measured" in text and "chi-square of the 3 entries" in text and "r_11" not in text


def test_the_export_of_a_joint_at_a_group_of_places_is_written(tmp_path, capsys):
    """The diagnosis names `pipe_II|ring_1` where the loads cannot tell the places apart; --export and --json had
    failed on that name ("no place 'pipe_II|ring_1' on this rod"), writing nothing."""
    sim, rec = tmp_path / "rod1.calc.json", tmp_path / "joint.rig.csv"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--design", "rod1", "--axes", "y,z", "--effect",
                 "joint_compliance:location=pipe_II,s_bend_rad_per_Nm=1e-4", "--repeats", "2", "--hold-s", "4",
                 "-o", str(rec)]) == 0
    capsys.readouterr()
    corr, report = tmp_path / "joint.corr.json", tmp_path / "joint.diag.json"
    assert main(["diagnose", "--rig", str(rec), "--sim", str(sim), "--design", "rod1", "--export", str(corr),
                 "--json", str(report)]) == 0
    err = capsys.readouterr().err
    data = json.loads(corr.read_text())
    finding = json.loads(report.read_text())["findings"][0]
    assert finding["effect"] == "joint_compliance"
    assert finding["location"] == "pipe_II|ring_1"              # y and z loads cannot tell the two apart
    assert "cannot tell these places apart" in err
    assert any("the file puts it at pipe_II" in w for w in data["provenance"]["warnings"])
    assert data["C_F_mm_per_N"][1][1] > json.loads(sim.read_text())["C_F_mm_per_N"][1][1]


def test_validate_accepts_a_recording_cut_off_in_its_last_line_as_the_readers_do(tmp_path, capsys):
    sim, rec = tmp_path / "rod1.calc.json", tmp_path / "cut.rig.csv"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--repeats", "1", "--hold-s", "3", "-o", str(rec)]) == 0
    text = rec.read_text()
    rec.write_text(text[:text.rstrip("\n").rfind("\n") + 1] + "233.000,30,2,unlo")     # the last sample cut off
    capsys.readouterr()
    assert main(["validate", str(rec)]) == 0
    out = capsys.readouterr()
    assert "valid, but with 1 warning" in out.out + out.err and "a sample cut off" in out.out + out.err
    bad = tmp_path / "mid.rig.csv"                     # a short line inside the file is still refused
    lines = text.splitlines()
    lines[len(lines) // 2] = lines[len(lines) // 2][:12]
    bad.write_text("\n".join(lines) + "\n")
    assert main(["validate", str(bad)]) != 0


def test_the_diagnosis_names_a_gauge_reversed_in_one_series_as_rig_fit_does(tmp_path, capsys):
    """The z gauge read reversed in the x series only: `rig fit` refuses it by reciprocity; the diagnosis had named a
    crosstalk at its bound, a tilted load line and a joint."""
    sim, rec = tmp_path / "rod1.calc.json", tmp_path / "flip.rig.csv"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--repeats", "2", "--hold-s", "4", "-o", str(rec)]) == 0
    def flip(cols, cells):
        axis, z = cols.index("load_axis"), cols.index("disp_z_mm")
        if cells[axis] == "x" and cells[z]:
            cells[z] = repr(-float(cells[z]))
    _edit_rows(rec, flip)
    capsys.readouterr()
    assert main(["diagnose", "--rig", str(rec), "--sim", str(sim)]) == 2
    err = capsys.readouterr().err
    assert "a gauge reversed in one series" in err and "nothing was diagnosed" in err


def test_tare_and_friction_are_fitted_beside_the_linear_compliance_they_bias(tmp_path, capsys):
    """At the default simulation accuracy the terms were built on the compliance fitted before them, which a tare
    biases: tare 0.111 kg [0.110, 0.113] for 0.120 and friction 0.527 N [0.525, 0.530] for 0.5 (intervals without
    the truth). They are now rebuilt on the compliance fitted beside them."""
    sim = tmp_path / "rod1.calc.json"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    for effect, key, true in (("tare:tare_kg=0.12", "tare_kg", 0.12), ("friction:F_f_N=0.5", "F_f_N", 0.5)):
        rec, report = tmp_path / f"{key}.rig.csv", tmp_path / f"{key}.diag.json"
        assert main(["rig", "simulate", "--sim", str(sim), "--effect", effect, "-o", str(rec)]) == 0
        assert main(["diagnose", "--rig", str(rec), "--sim", str(sim), "--json", str(report)]) == 0
        found = json.loads(report.read_text())
        assert found["verdict"] == "explained"
        finding = next(f for f in found["findings"] if key in f["parameters"])
        assert finding["parameters"][key] == pytest.approx(true, rel=0.02)
        low, high = finding["intervals_95"][key]
        assert low <= true <= high


def test_following_updates_advice_for_a_joint_writes_the_as_built_design(tmp_path, capsys):
    """The refusal names the joint's key to free; freeing it had been refused again (the joint's prior, 100 sound
    bonds, held a 2e-3 rad/(N m) joint at 1.7e-3): the joint's size is now the data's."""
    from conftest import SHARED
    import re

    design = SHARED / "examples" / "rods" / "rod1.rod.toml"
    if not design.exists():
        pytest.skip("../shared/examples is not present beside the repository")
    sim, rec, out = tmp_path / "sim.json", tmp_path / "joint.rig.csv", tmp_path / "asbuilt.rod.toml"
    assert main(["fea", str(design), "--model", "frame", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--design", str(design), "--effect",
                 "joint_compliance:location=pipe_II,s_bend_rad_per_Nm=2e-3", "--repeats", "2", "--hold-s", "4",
                 "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["update", str(design), "--measured", str(rec), "-o", str(out)]) == 3
    keys = re.search(r"--free ([\w.,]+)\)", capsys.readouterr().err).group(1)
    assert "joints.pipe_II.s_bend_rad_per_Nm" in keys
    assert main(["update", str(design), "--measured", str(rec), "-o", str(out), "--free", keys]) == 0
    s = float(re.search(r"joints.pipe_II.s_bend_rad_per_Nm\s+\S+\s+(\S+)", capsys.readouterr().out).group(1))
    assert abs(s / 2e-3 - 1) < 0.05 and out.exists()


def test_masses_in_grams_with_readings_in_um_are_named(tmp_path, capsys, caplog):
    """The slopes come out right (both 1000x), the noise, friction and zero crossings do not: it had passed silently."""
    sim, rec = tmp_path / "rod1.calc.json", tmp_path / "g.rig.csv"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--repeats", "1", "--hold-s", "3", "-o", str(rec)]) == 0
    def thousandfold(cols, cells):
        for name in ("mass_kg", "disp_x_mm", "disp_y_mm", "disp_z_mm"):
            j = cols.index(name)
            if cells[j]:
                cells[j] = f"{float(cells[j]) * 1000:.4f}"
    _edit_rows(rec, thousandfold)
    with caplog.at_level("WARNING"):
        assert main(["rig", "fit", str(rec), "--sim", str(sim), "-o", str(tmp_path / "g.json")]) == 0
    assert "if these are grams, divide mass_kg by 1000" in caplog.text


def test_did_you_mean_keeps_a_typos_first_letter_or_a_word_of_the_name():
    from rodlab.core.errors import did_you_mean
    cols = ["time_s", "step", "repeat", "phase", "load_axis", "mass_kg", "disp_x_mm", "disp_y_mm", "disp_z_mm"]
    assert did_you_mean("Achse", cols) == ""                     # German for axis: not `phase`
    assert "`load_axis`" in did_you_mean("axis", cols)           # a word of the name
    assert "`mass_kg`" in did_you_mean("mas_kg", cols)           # a typo
