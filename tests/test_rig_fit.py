"""Stiffness-rig recordings and fitting: the contract examples, Eq. 21/22, malformed files."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab import Method, read_compliance
from rodlab.core.units import G0
from rodlab.stiffness_rig import RecordingWriter, RigError, fit_recording, read_recording
from conftest import rewrite_recording


@pytest.fixture
def sim(examples):
    return read_compliance(examples / "rod1.compliance.json")


@pytest.mark.parametrize("name", ["null", "joint_compliance-ring_1", "friction"])
def test_recovers_true_compliance(examples, sim, name):
    rec = read_recording(examples / f"rig-{name}.rig.csv")
    truth = json.loads((examples / f"rig-{name}.truth.json").read_text())
    T = np.array(truth["C_F_true_mm_per_N"])
    fit = fit_recording(rec, sim)
    measured = np.isfinite(fit.C_F_meas) & (np.abs(T) > 1e-3 * np.abs(T).max())
    np.testing.assert_allclose(fit.C_F_meas[measured], T[measured], rtol=0.01)
    assert fit.noise_mm == pytest.approx(truth["noise_rms_mm"], rel=0.15)    # within-hold scatter
    assert fit.success


def test_friction_intercepts_in_kg(examples, sim):
    rec = read_recording(examples / "rig-friction.rig.csv")
    Ff = json.loads((examples / "rig-friction.truth.json").read_text())["parameters"]["F_f_N"]
    fit = fit_recording(rec, sim)
    for ln in fit.lines:
        if ln.component == ln.axis.index:
            half_split = 0.5 * (ln.zero_load_kg["load"] - ln.zero_load_kg["unload"])
            assert half_split == pytest.approx(Ff / G0, rel=0.15), ln.axis
            assert ln.zero_load_kg["load"] > 0 > ln.zero_load_kg["unload"]
    null = fit_recording(read_recording(examples / "rig-null.rig.csv"), sim)
    for ln in null.lines:
        if ln.component == ln.axis.index:
            assert abs(ln.zero_load_kg["load"] - ln.zero_load_kg["unload"]) < 0.1 * Ff / G0


def test_zero_load_from_the_unloaded_reference_not_the_gauge_zero(examples, sim, tmp_path):
    """A gauge zeroed on one reading sits that reading's noise off: the crossings are taken from the unloaded
    reference hold, so a constant offset of every reading moves none of them (it had read as a +15 g dead load at
    18 standard errors on an independent null recording)."""
    src = examples / "rig-null.rig.csv"

    def offset(i, row):
        for c in ("disp_x_mm", "disp_y_mm", "disp_z_mm"):
            if row.get(c):
                row[c] = f"{float(row[c]) + 0.004:.6f}"
    shifted = fit_recording(read_recording(rewrite_recording(src, tmp_path / "off.rig.csv", offset)), sim)
    plain = fit_recording(read_recording(src), sim)
    for a, b in zip(plain.lines, shifted.lines):
        if a.component != a.axis.index:
            continue
        for phase in ("load", "unload"):
            assert b.zero_load_kg[phase] == pytest.approx(a.zero_load_kg[phase], abs=1e-9)
            assert abs(b.zero_load_kg[phase]) < 3 * b.zero_load_se_kg[phase]      # a null: no dead load


def test_measured_compliance_file(examples, sim, tmp_path):
    from rodlab import write_compliance
    rec = read_recording(examples / "rig-null.rig.csv")
    fit = fit_recording(rec, sim)
    comp = fit.compliance(sim, rec)
    assert comp.method is Method.MEAS
    np.testing.assert_allclose(comp.C_g, fit.r_rod * sim.C_g)                          # Eq. 22
    r = (fit.C_F_meas[1, 1] + fit.C_F_meas[2, 2]) / (sim.C_F[1, 1] + sim.C_F[2, 2])
    assert fit.r_rod == pytest.approx(r)                                                # Eq. 21
    np.testing.assert_allclose(comp.C_F, comp.C_F.T)
    back = read_compliance(write_compliance(comp, tmp_path / "m.compliance.json"))
    assert back.provenance["recording_sha256"] and back.r_rod == pytest.approx(fit.r_rod)


def test_robust_fit_resists_an_outlier_hold(examples, sim):
    rec = read_recording(examples / "rig-null.rig.csv")
    bad = rec.step == rec.steps()[20]
    rec.disp_mm[bad, 1] += 0.05                                         # a mislabelled / bumped hold
    plain = fit_recording(rec, sim)
    robust = fit_recording(rec, sim, robust=True)
    T = sim.C_F[1, 1]
    assert abs(robust.C_F_meas[1, 1] / T - 1) < abs(plain.C_F_meas[1, 1] / T - 1)


HEADER = "# format: rodlab.rig/1\n# rod: 1#\ntime_s,step,repeat,phase,load_axis,mass_kg,disp_x_mm,disp_y_mm,disp_z_mm\n"
GOOD = ["0.0,1,1,load,y,0.0,,0.000,0.000", "0.1,1,1,load,y,0.0,,0.001,0.000",
        "1.0,2,1,load,y,0.5,,1.000,0.000", "1.1,2,1,load,y,0.5,,1.001,0.000"]
BAD = [
    ("missing column", HEADER.replace(",disp_z_mm", ""), GOOD, 3, "disp_z_mm", "missing"),
    ("extra column", HEADER.replace("disp_z_mm", "disp_z_mm,force_kN"), [g + ",1" for g in GOOD], 3, "force_kN",
     "unknown column"),
    # an instrument trial: disp_w_mm beside disp_x/z had been told "did you mean disp_z_mm", a column it has
    ("near-miss column", HEADER.replace("disp_y_mm", "disp_w_mm"), GOOD, 3, "disp_w_mm", "Did you mean `disp_y_mm`"),
    ("bad force", HEADER.replace("disp_z_mm", "disp_z_mm,force_N"), [g + ",0.0" for g in GOOD[:2]]
     + ["1.0,2,1,load,y,0.5,,1.0,0.0,heavy"], 6, "force_N", "number"),
    ("non-numeric", HEADER, GOOD[:2] + ["1.0,2,1,load,y,0.5,,abc,0.000"], 6, "disp_y_mm", "number"),
    ("unknown axis", HEADER, GOOD[:2] + ["1.0,2,1,load,w,0.5,,1.0,0.000"], 6, "load_axis", "unknown load axis"),
    ("bad phase", HEADER, GOOD[:2] + ["1.0,2,1,loading,y,0.5,,1.0,0.000"], 6, "phase", "load"),
    ("mass changes in hold", HEADER, GOOD[:3] + ["1.1,2,1,load,y,0.6,,1.0,0.000"], 7, "mass_kg", "inside hold"),
    ("axis changes in hold", HEADER, GOOD[:3] + ["1.1,2,1,load,z,0.5,,1.0,0.000"], 7, "load_axis", "inside hold"),
    ("no zero hold", HEADER, ["0.0,1,1,load,y,0.5,,1.0,0.0", "0.1,1,1,load,y,0.5,,1.0,0.0"], 4, "mass_kg",
     "mass-0 hold"),
    ("wrong cell count", HEADER, GOOD[:2] + ["1.0,2,1,load,y,0.5,,1.0"] + GOOD[2:3], 6, None, "cells"),   # not last
    ("negative mass", HEADER, GOOD[:2] + ["1.0,2,1,load,y,-0.5,,1.0,0.0"], 6, "mass_kg", ">= 0"),
    ("nan", HEADER, GOOD[:2] + ["1.0,2,1,load,y,nan,,1.0,0.0"], 6, "mass_kg", "finite"),
    ("huge step", HEADER, GOOD[:2] + ["1.0,1e308,1,load,y,0.5,,1.0,0.0"], 6, "step", "below 2^31"),
    ("time backwards", HEADER, GOOD[:2] + ["0.05,2,1,load,y,0.5,,1.0,0.0"], 6, "time_s", "Split the file"),
    # rows shuffled (a new user's trial): not two recordings joined, so not "split the file" but sort it
    ("rows shuffled", HEADER, [GOOD[2], GOOD[0], GOOD[3], GOOD[1]], 5, "time_s", "Sort the data rows by time_s"),
    ("no format", HEADER.replace("# format: rodlab.rig/1\n", ""), GOOD, 1, "format", "format"),
]


@pytest.mark.parametrize("label,header,rows,line,key,words", BAD, ids=[b[0] for b in BAD])
def test_malformed_recording(tmp_path, label, header, rows, line, key, words):
    p = tmp_path / "bad.rig.csv"
    p.write_text(header + "\n".join(rows) + "\n")
    with pytest.raises(RigError) as ei:
        read_recording(p)
    e = ei.value
    assert e.line == line and e.key == key and words in str(e) and str(p) in str(e), str(e)


def test_writer_appends_and_cuts_a_torn_line(tmp_path):
    p = tmp_path / "r.rig.csv"
    with RecordingWriter(p, {"rod": "1#"}) as w:
        w.write(0.0, 1, 1, "load", "y", 0.0, (float("nan"), 0.0, 0.0), 20.0)
        w.write(0.1, 1, 1, "load", "y", 0.0, (float("nan"), 0.001, 0.0), 20.0)
    with open(p, "a") as fh:
        fh.write("0.2,1,1,lo")                        # a crash mid-line
    with RecordingWriter(p, {"rod": "1#"}) as w:      # reopening keeps every complete line, cuts the torn one
        w.write(1.0, 2, 1, "load", "y", 0.5, (float("nan"), 1.0, 0.0), 20.0)
        w.write(1.1, 2, 1, "load", "y", 0.5, (float("nan"), 1.0, 0.0), 20.0)
    rec = read_recording(p)
    assert rec.n == 4 and np.isnan(rec.disp_mm[:, 0]).all() and rec.temp_C is not None


def test_fig8_numbers_read_at_a_glance():
    """Standard errors keep two significant digits (not '+- 0.00'); zero crossings in grams, never '-0.000 kg'
    or '+nan'."""
    from rodlab.stiffness_rig.plot import format_pm, format_zero
    assert format_pm(219.8012, 0.00312, "um/N") == "219.8012 +- 0.0031 um/N"
    assert format_pm(6.2792, 0.028, "um/N") == "6.279 +- 0.028 um/N"
    assert [format_zero(z) for z in (-4.2e-5, -0.006, 0.0123, 0.0, float("nan"))] == [
        "-0.042 g", "-6.0 g", "+12 g", "0 g", "n/a"]


def _scaled_copy(src, dst, mass=1.0, disp=1.0, rod=None, bom=False):
    """A copy of a recording with its masses and readings scaled (a units slip), another rod name, or a BOM."""
    def scale(_, row):
        for name, cell in row.items():
            if cell and (name == "mass_kg" or name.startswith("disp_")):
                row[name] = repr(float(cell) * (mass if name == "mass_kg" else disp))
    return rewrite_recording(src, dst, scale, lambda line: f"# rod: {rod}" if rod and line.startswith("# rod:") else line,
                             "\ufeff" if bom else "")


@pytest.mark.parametrize("mass, disp", [(1000.0, 1.0), (1.0, 1000.0)])
def test_a_units_slip_is_refused_with_what_to_check(examples, sim, tmp_path, mass, disp):
    """Masses in g or readings in um gave r_rod 0.001 (written silently) or an error about r_mn's schema bounds."""
    import subprocess
    import sys
    bad = _scaled_copy(examples / "rig-null.rig.csv", tmp_path / "bad.rig.csv", mass, disp)
    fit = fit_recording(read_recording(bad), sim)
    assert not fit.success and "units" in fit.message and "mass_kg in kg" in fit.message
    run = subprocess.run([sys.executable, "-m", "rodlab", "rig", "fit", str(bad), "--sim", str(examples / "rod1.compliance.json"),
                          "-o", str(tmp_path / "out.json")], capture_output=True, text=True)
    assert run.returncode != 0 and "units" in run.stderr and not (tmp_path / "out.json").exists()


def test_another_rods_recording_is_refused_and_a_bom_is_read(examples, tmp_path):
    """`rig fit` writes a compliance file: of one rod's recording and another's simulation it would mix the two
    (found by a new user: exit 0 and a file naming the simulation's rod with the other rod's C_F)."""
    import subprocess
    import sys
    other = _scaled_copy(examples / "rig-null.rig.csv", tmp_path / "o.rig.csv", rod="6#", bom=True)
    assert read_recording(other).rod == "6#"
    run = subprocess.run([sys.executable, "-m", "rodlab", "rig", "fit", str(other), "--sim",
                          str(examples / "rod1.compliance.json"), "-o", str(tmp_path / "out.json")],
                         capture_output=True, text=True)
    assert run.returncode != 0 and "of rod '6#'" in run.stderr and "Give --sim this rod's simulation" in run.stderr
    assert not (tmp_path / "out.json").exists()
    same = _scaled_copy(examples / "rig-null.rig.csv", tmp_path / "s.rig.csv", rod="rod1")
    run = subprocess.run([sys.executable, "-m", "rodlab", "rig", "fit", str(same), "--sim",
                          str(examples / "rod1.compliance.json"), "-o", str(tmp_path / "out2.json")],
                         capture_output=True, text=True)
    assert run.returncode == 0 and "warning" not in run.stderr, run.stderr


def test_diagnose_refuses_an_implausible_r_rod(examples, tmp_path):
    """Masses in g (r_rod 0.001): refused with the units named; --units-checked diagnoses with the warning."""
    import subprocess
    import sys
    bad = _scaled_copy(examples / "rig-null.rig.csv", tmp_path / "bad.rig.csv", mass=1000.0)
    cmd = [sys.executable, "-m", "rodlab", "diagnose", "--rig", str(bad), "--sim", str(examples / "rod1.compliance.json")]
    run = subprocess.run(cmd, capture_output=True, text=True)
    assert run.returncode == 2 and "r_rod = 0.001" in run.stderr and "mass_kg in kg" in run.stderr
    assert "nothing was diagnosed" in run.stderr
    run = subprocess.run(cmd + ["--units-checked"], capture_output=True, text=True)
    assert run.returncode in (0, 3) and "warning: r_rod = 0.001" in run.stderr
