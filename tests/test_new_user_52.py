"""A lab technician's trial (2026-11-29, helper-52): an interrupted run's unmeasured entry, a truncated last line,
the diagnosis's export of a joint it could not place to one part, a gauge reversed in one series."""
from __future__ import annotations

import json

from rodlab.app.cli import main


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
