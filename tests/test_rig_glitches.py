"""One reading far off its hold's line (a gauge's cut-off answer, an electrical spike): `rig fit` leaves it out
and says where (an instrument trial: a 59 um reading had made the noise 1.46 um instead of 0.5 um and c33's
standard error 10x the others', without a word); the diagnosis finds the same readings (one shared module)."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.app.cli.main import main
from rodlab.stiffness_rig import fit_recording, read_recording
from rodlab.stiffness_rig.glitches import glitch_rows


def _spiked(tmp_path):
    clean = tmp_path / "clean.rig.csv"
    assert main(["rig", "simulate", "--sim", "rod1", "--noise-um", "0.5", "--repeats", "2", "--seed", "4",
                 "-o", str(clean)]) == 0
    lines = clean.read_text().splitlines()
    head = next(i for i, ln in enumerate(lines) if ln.startswith("time_s"))
    k = head + 1 + 400                       # a reading inside a loaded hold
    cells = lines[k].split(",")
    cells[8] = f"{float(cells[8]) + 0.059:.6f}"           # disp_z_mm 59 um off
    lines[k] = ",".join(cells)
    spiked = tmp_path / "spiked.rig.csv"
    spiked.write_text("\n".join(lines) + "\n")
    return clean, spiked, int(cells[1])


def test_rig_fit_leaves_a_glitch_out_and_names_its_hold(tmp_path):
    clean, spiked, step = _spiked(tmp_path)
    rows, comps, off = glitch_rows(read_recording(spiked))
    assert rows.size == 1 and comps[0] == 2 and off[0] == pytest.approx(0.059, abs=0.003)
    ref, fit = fit_recording(read_recording(clean)), fit_recording(read_recording(spiked))
    assert fit.noise_mm == pytest.approx(ref.noise_mm, rel=0.05)
    m = np.isfinite(ref.C_F_meas)
    assert np.allclose(fit.C_F_meas[m], ref.C_F_meas[m], rtol=2e-3, atol=1e-7)
    assert np.nanmax(fit.C_F_se) < 1.5 * np.nanmax(ref.C_F_se)
    said = [w for w in fit.warnings if "single reading" in w]
    assert said and f"step {step}" in said[0] and "59" in said[0]
    assert not any("single reading" in w for w in ref.warnings)


def test_the_cli_says_so_and_writes_the_file(tmp_path, capsys):
    _, spiked, step = _spiked(tmp_path)
    out = tmp_path / "m.json"
    assert main(["rig", "fit", str(spiked), "--sim", "rod1", "-o", str(out)]) == 0
    assert f"(step {step}; up to 5" in capsys.readouterr().err and out.exists()


def test_a_jump_within_a_hold_is_no_pair_of_glitches(tmp_path):
    """A gauge slipping by 20 um halfway through a hold leaves the two readings next to the jump off the hold's
    line (a review: `rig fit` had called them two glitches); the level changing across them says it is a jump."""
    clean, _, _ = _spiked(tmp_path)
    rec = read_recording(clean)
    step = int(rec.step[400])
    rows = np.flatnonzero(rec.step == step)
    disp = rec.disp_mm.copy()
    disp[rows[rows.size // 2]:rows[-1] + 1, 2] += 0.020
    import dataclasses
    jumped = dataclasses.replace(rec, disp_mm=disp)
    assert glitch_rows(jumped)[0].size == 0
    assert not any("single reading" in w for w in fit_recording(jumped).warnings)
