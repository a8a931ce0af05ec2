"""The measured side of the rig fit: per-entry factors r_mn (Eq. 20) and the measured C_F's uncertainty in the
measured compliance file (rodlab.compliance/2), and a load cell's force_N instead of mass x g0."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import calc_rod_compliance, read_compliance, resolve_design, write_compliance
from conftest import legacy_design
from rodlab.stiffness_rig import fit_recording, read_recording
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

SIM = calc_rod_compliance(legacy_design("rod1"))     # the rod 1# the rig machinery was sized on (conftest)
QUICK = LoadSchedule(axes=("y", "z", "x"), masses=(0.5, 1.0, 1.5, 2.0), repeats=2, hold_s=4.0, rate_Hz=10.0)


def _record(tmp_path, effects=None, scale=1.0, **model_kw):
    C = SIM.C_F * scale
    model = RigModel(C, effects or {}, seed=3, **model_kw)
    return read_recording(simulate_recording(model, QUICK, tmp_path / "r.rig.csv", rod=SIM.rod)), model


def test_measured_file_stores_r_mn_and_sigma(tmp_path):
    """A rod 8 % more compliant than simulated: every measured entry's r_mn is 1.08, unmeasured ones (load x
    measured y, load y measured x, ...) are null, C_F_sigma is the fit's standard error where measured; the file
    is rodlab.compliance/2 and reads back the same."""
    rec, _ = _record(tmp_path, scale=1.08)
    fit = fit_recording(rec, SIM)
    comp = fit.compliance(SIM, rec)
    sig = np.abs(SIM.C_F) > 1e-6 * np.abs(SIM.C_F).max()
    measured = np.isfinite(fit.C_F_meas)
    np.testing.assert_allclose(comp.r_mn[measured & sig], 1.08, rtol=2e-3)
    assert np.isnan(comp.r_mn[~measured]).all() and np.isnan(comp.r_mn[~sig]).all()
    np.testing.assert_array_equal(np.isfinite(comp.C_F_sigma), measured)
    np.testing.assert_allclose(comp.C_F_sigma[measured], fit.C_F_se[measured])
    back = read_compliance(write_compliance(comp, tmp_path / "m.compliance.json"))
    assert back.format_id == "rodlab.compliance/2"
    np.testing.assert_allclose(back.r_mn, comp.r_mn, rtol=1e-8)
    assert fit.r_rod == pytest.approx(1.08, rel=2e-3)


def test_load_cell_measures_friction_and_tare_and_the_fit_needs_no_friction(tmp_path):
    """Friction in the slides (0.4 N) and a hanger missing from mass_kg (60 g): with a load cell (noise 0.01 N)
    the lines are fitted against the force the rod carries, so the branches meet at zero load (no friction
    hypothesis needed), every measured entry is the truth, and mass x g0 - force_N per branch gives the friction
    within 10 % and the tare within 10 %. Without the load cell the same rig splits the branches by the
    friction."""
    from rodlab.core.units import G0
    effects = {"friction": {"F_f_N": 0.4}, "tare": {"tare_kg": 0.06}}
    rec, model = _record(tmp_path, effects, load_cell_noise_N=0.01)
    assert rec.has_force
    fit = fit_recording(rec, SIM)
    ok = np.isfinite(fit.C_F_meas) & (np.abs(SIM.C_F) > 1e-3 * np.abs(SIM.C_F).max())
    np.testing.assert_allclose(fit.C_F_meas[ok], model.C_true[ok], rtol=2e-3)
    for ln in fit.lines:
        if ln.component == ln.axis.index:
            split = ln.zero_load_kg["load"] - ln.zero_load_kg["unload"]
            assert abs(split) < 0.1 * 0.4 / G0, (ln.axis, split)
    load = fit.load
    assert set(load.friction_N) == {a for a in set(rec.load_axis)}
    for axis, ff in load.friction_N.items():
        assert ff == pytest.approx(0.4, rel=0.10), axis
        assert load.tare_kg[axis] == pytest.approx(0.06, rel=0.10), axis
    for b in load.branches:                      # per branch: +F_f - tare g0 loading, -F_f - tare g0 unloading
        expect = (0.4 if b.phase.value == "load" else -0.4) - 0.06 * G0
        assert b.diff_N == pytest.approx(expect, abs=0.04), b
    assert load.force_noise_N == pytest.approx(0.01, rel=0.2)
    assert fit.compliance(SIM, rec).provenance["measured_load"]["friction_N"]

    nominal, _ = _record(tmp_path / "n", effects)                       # the same rig without a load cell
    nfit = fit_recording(nominal, SIM)
    assert nfit.load is None and not nominal.has_force
    yy = next(ln for ln in nfit.lines if ln.axis.value == "y" and ln.component == 1)
    assert yy.zero_load_kg["load"] - yy.zero_load_kg["unload"] == pytest.approx(2 * 0.4 / G0, rel=0.1)


def test_diagnosis_uses_the_measured_load(tmp_path):
    """diagnose --rig on a friction rig: without a load cell friction is found; with one (noise 5 mN) the load
    already carries the friction: no friction finding, and RigSamples.F is the hold's mean force."""
    from rodlab.app.diagnose import diagnose_rig
    from rodlab.stiffness_rig.samples import rig_samples
    effects = {"friction": {"F_f_N": 0.5}}
    nominal, _ = _record(tmp_path / "n", effects)
    names = {f.effect for f in diagnose_rig(nominal, SIM)[0].findings}
    assert "friction" in names
    rec, _ = _record(tmp_path, effects, load_cell_noise_N=0.005)
    data = rig_samples(rec)
    k = np.nonzero(data.mass > 0)[0][0]
    hold = rec.step == data.step[k]
    assert data.F[k] == pytest.approx(np.mean(rec.force_N[hold]) * data.sign[k])
    assert abs(data.F[k]) != pytest.approx(data.mass[k] * 9.80665, abs=0.1)
    assert 0 < data.F_se[k] < 0.005
    names = {f.effect for f in diagnose_rig(rec, SIM)[0].findings}
    assert "friction" not in names and "tare" not in names, names


def test_force_column_round_trip_and_partial_load_cell(tmp_path, caplog):
    """The writer's force_N column reads back (empty cells NaN); a load cell that read on some holds only is not
    mixed with nominal loads: the fit falls back to mass x g0 on every hold and says so."""
    from rodlab.stiffness_rig import RecordingWriter
    p = tmp_path / "w.rig.csv"
    rows = [(0.0, 1, 0.0, 0.0, 0.01), (0.1, 1, 0.0, 0.0, float("nan"))]
    for k, m in enumerate((0.5, 1.0, 1.5, 1.0, 0.5, 0.0)):
        for j in range(3):
            rows.append((1.0 + k + 0.1 * j, k + 2, m, m * 9.80665 * 0.2, m * 9.80665 if k != 2 else float("nan")))
    with RecordingWriter(p, {"rod": "1#"}, with_force=True) as w:
        for t, step, m, y, f in rows:
            phase = "load" if step <= 4 or step == 1 else "unload"
            w.write(t, step, 1, phase, "y", m, (float("nan"), y, 0.0), 21.0, f)
    rec = read_recording(p)
    assert rec.has_force and np.isnan(rec.force_N[1]) and rec.force_N[0] == pytest.approx(0.01)
    with caplog.at_level("WARNING"):
        fit = fit_recording(rec)
    assert fit.load is None and "read on" in caplog.text
    assert fit.C_F_meas[1, 1] == pytest.approx(0.2, rel=1e-3)


def test_plan_beyond_the_carbon_linear_range_names_the_holds(tmp_path, capsys):
    """The paper's own schedule hangs 2 kg (19.6 N > 15 N) on the carbon rod 1#: one warning naming those holds
    (5/123 is the first: after the zero hold and 0.5, 1.0, 1.5 kg); the stainless rod 4# and a schedule up to
    1.5 kg (14.7 N) get none. rig simulate prints it."""
    from rodlab.app.cli import main
    from rodlab.stiffness_rig.config import read_plan
    from rodlab.stiffness_rig.plan_check import linear_range_warnings
    from conftest import ROOT
    plan = read_plan(ROOT / "stiffness_rig" / "plans" / "paper.plan.toml")
    w = linear_range_warnings(plan.schedule, resolve_design("rod1"))
    assert len(w) == 1 and "2 kg" in w[0] and "19.6 N" in w[0] and "hold 5/123 (y, load, repeat 1)" in w[0]
    assert "and 11 more" in w[0]                               # 15 holds of 2 kg: 5 repeats x 3 axes
    assert linear_range_warnings(plan.schedule, resolve_design("rod4")) == []
    assert linear_range_warnings(LoadSchedule(masses=(0.5, 1.0, 1.5)), resolve_design("rod1")) == []
    import dataclasses                                        # a laminate of the user's under another name
    from rodlab.core.materials import Material
    rod1 = resolve_design("rod1")
    own = Material("cf_own", 110.0, 0.3, 1580.0, E_transverse_GPa=9.0, G_GPa=12.0)
    mine = dataclasses.replace(rod1, pipe_I=dataclasses.replace(rod1.pipe_I, material=own),
                               pipe_II=dataclasses.replace(rod1.pipe_II, material=own))
    assert len(linear_range_warnings(plan.schedule, mine)) == 1
    sim = write_compliance(SIM, tmp_path / "s.compliance.json")
    assert main(["rig", "simulate", "--sim", str(sim), "--repeats", "1", "--masses", "1,2", "-o",
                 str(tmp_path / "r.rig.csv")]) == 0
    err = capsys.readouterr().err
    assert "warning: 2 kg loads the carbon rod 1#" in err and "hold 3/15 (y, load, repeat 1)" in err


def test_default_plan_stays_within_a_carbon_rods_linear_range(tmp_path, capsys):
    """Without --masses, rig simulate loads the carbon rod 1# with the paper's masses up to 1.5 kg (14.7 N) and
    warns of nothing; the stainless rod 4# gets the paper's whole schedule, 2 kg included."""
    from rodlab.app.cli import main
    from rodlab.stiffness_rig import default_masses, read_recording
    assert default_masses(resolve_design("rod1")) == (0.5, 1.0, 1.5)
    assert default_masses(resolve_design("rod4")) == (0.5, 1.0, 1.5, 2.0) == default_masses(None)
    for rod, heaviest, holds in (("rod1", 1.5, 93), ("rod4", 2.0, 123)):
        path = tmp_path / f"{rod}.rig.csv"
        assert main(["rig", "simulate", "--sim", rod, "-o", str(path)]) == 0
        out = capsys.readouterr()
        assert "warning" not in out.err and f"{holds} holds" in out.out
        assert read_recording(path).mass_kg.max() == heaviest


def test_a_hold_shorter_than_one_sample_is_refused(tmp_path, capsys):
    """--hold-s 0.04 at 10 Hz would write a recording with only its header: refused, naming the key and the fix."""
    from rodlab.app.cli import main
    out = tmp_path / "q.rig.csv"
    assert main(["rig", "simulate", "--sim", "rod1", "--hold-s", "0.04", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "rodlab rig simulate: error: key `hold_s`" in err and "takes no sample" in err and not out.exists()


def test_a_schedule_of_endless_repeats_is_refused_from_python():
    """``LoadSchedule(repeats=...)`` as an acquisition script may change it: inf and an int beyond any float are
    refused naming ``repeats`` (both had been an OverflowError)."""
    import math
    from rodlab.stiffness_rig.errors import RigError
    from rodlab.stiffness_rig.model import LoadSchedule
    for repeats in (math.inf, 10 ** 400):
        with pytest.raises(RigError, match="repeats"):
            LoadSchedule(repeats=repeats)


def test_a_hold_of_absurdly_many_samples_is_refused_in_the_plan_file(tmp_path):
    """A plan file's hold_s = 1e308 or repeats = 1e308 (each found by the readers' fuzzing: an OverflowError
    traceback) or a hold in ms written as s: refused naming the file, the key and the likely slip."""
    from rodlab.core.errors import RodlabError
    from conftest import ROOT
    from rodlab.stiffness_rig.config import read_plan
    src = ROOT / "stiffness_rig" / "plans" / "paper.plan.toml"
    for hold in ("1e308", "8000000.0"):
        bad = tmp_path / "bad.plan.toml"
        bad.write_text(src.read_text().replace("hold_s = 8.0", f"hold_s = {hold}"))
        with pytest.raises(RodlabError, match=r"bad\.plan\.toml.*hold_s.*is hold_s in seconds"):
            read_plan(bad)
    for old, new, key in (("rate_Hz = 10.0", "rate_Hz = 1e7", "rate_Hz"), ("repeats = 5", "repeats = 1000000", "repeats"),
                          ("repeats = 5", "repeats = 1e308", "repeats")):    # 1e308 holds: an int beyond any float
        bad.write_text(src.read_text().replace(old, new))             # the whole plan too long, the key named
        with pytest.raises(RodlabError, match=rf"bad\.plan\.toml.*{key}.*more than a plan's 1e\+08"):
            read_plan(bad)


def test_the_default_plan_knows_a_carbon_rod_from_its_design_file(tmp_path, capsys):
    """A compliance file of a user's carbon design (not a built-in name) gets the carbon default through the design
    file its provenance names; a file with no design gets the paper's masses and a note saying why."""
    import json

    from conftest import ROOT
    from rodlab.app.cli import main
    text = (ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml").read_text()
    lines = [('name = "myrod"' if ln.startswith("name") else ln) for ln in text.splitlines()]
    (tmp_path / "my.rod.toml").write_text("\n".join(lines) + "\n")
    assert main(["fea", str(tmp_path / "my.rod.toml"), "--model", "calc", "-o", str(tmp_path / "my.json")]) == 0
    capsys.readouterr()
    assert main(["rig", "simulate", "--sim", str(tmp_path / "my.json"), "-o", str(tmp_path / "a.rig.csv")]) == 0
    assert "93 holds (masses 0.5, 1, 1.5 kg) on rod myrod" in capsys.readouterr().out
    data = json.loads((tmp_path / "my.json").read_text())
    data["provenance"].pop("design_file")
    (tmp_path / "anon.json").write_text(json.dumps(data))
    assert main(["rig", "simulate", "--sim", str(tmp_path / "anon.json"), "-o", str(tmp_path / "b.rig.csv")]) == 0
    out = capsys.readouterr()
    assert "123 holds" in out.out and "the rod's design is unknown" in out.err
