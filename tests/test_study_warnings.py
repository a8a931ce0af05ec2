"""What the study says beyond its numbers (rodlab.app.study.design_warnings) and a recommendation that never
sends a designer to a rod that makes the robot less accurate when another one helps."""
from __future__ import annotations

import math

import pandas as pd
import pytest

from rodlab.app.study import recommend, study_warnings
from rodlab.app.study.table import STUDY_COLUMNS
from rodlab.core.enums import StudyWarning


def _rows(design, c_rod, means, nominal, slip_share, mass=1.0):
    return [dict({c: math.nan for c in STUDY_COLUMNS}, design=design, status="ok", method=m, mean_mm=v,
                 mean_p05_mm=0.9 * v, mean_p95_mm=1.1 * v, nominal_mean_mm=nominal, share_slip=slip_share,
                 c_rod_um=c_rod, mass_kg=mass, L1_mm=300.0, L2_mm=450.0)
            for m, v in zip(("none", "fea", "meas"), means)]


def _table(*designs):
    return pd.DataFrame([r for d in designs for r in d])[STUDY_COLUMNS]


def test_a_rod_that_harms_is_warned_about_and_not_recommended():
    stiff = _rows("stiff", 60.0, (0.30, 0.25, 0.20), 1.6, 0.3, mass=1.4)
    soft = _rows("soft", 6600.0, (2.5, 2.4, 2.36), 1.6, 0.99, mass=0.6)
    df = _table(stiff, soft)
    kinds = {(w.design, w.kind) for w in study_warnings(df, rod_slip=2.4)}
    assert kinds == {("soft", StudyWarning.WORSE_THAN_NOMINAL), ("soft", StudyWarning.SLIP_DOMINATES),
                     ("soft", StudyWarning.SLIP_EXTRAPOLATED)}
    rec = recommend(df)
    assert rec.design == "stiff"                       # the lighter soft rod would do harm: left out, and said
    assert "1 of 2 designs" in rec.text and "less accurate than uncalibrated" in rec.text


def test_a_lighter_harmful_design_within_the_best_band_is_left_out_and_warned_by_the_same_rule():
    """The harmful design is lighter and within the best one's band, so without the rule it would be picked; its
    fea helps and meas (the recommendation's method) harms: the warning and the recommendation judge by meas."""
    best = _rows("best", 60.0, (0.30, 0.25, 1.500), 1.6, 0.3, mass=1.4)
    light = _rows("light", 70.0, (0.30, 0.90, 1.650), 1.6, 0.3, mass=0.6)
    light[2]["mean_p05_mm"] = 1.40                  # inside best's band (1.35-1.65) if the rule were off
    df = _table(best, light)
    rec = recommend(df)
    assert rec.design == "best" and "1 of 2 designs" in rec.text
    warned = [w for w in study_warnings(df, rod_slip=0.0) if w.design == "light"]
    assert [w.kind for w in warned] == [StudyWarning.WORSE_THAN_NOMINAL]
    assert "with meas compensation" in warned[0].text and "fea 0.900 mm would not" in warned[0].text
    assert study_warnings(_table(best), rod_slip=0.0) == []


def test_when_every_rod_harms_the_recommendation_says_so():
    df = _table(_rows("soft", 6600.0, (2.5, 2.4, 2.36), 1.6, 0.99))
    rec = recommend(df)
    assert rec.design == "soft" and "no design improves on the robot's nominal model (1.600 mm" in rec.text


def test_without_slip_no_slip_warning_and_the_paper_rods_pass_quietly():
    """At --rod-slip 0 the slip warnings cannot fire; a carbon rod like 1# (slip 60 % of its error, c_rod within the
    paper's range) gets none."""
    soft = _rows("soft", 6600.0, (1.2, 0.6, 0.28), 1.8, 0.0)
    assert study_warnings(_table(soft), rod_slip=0.0) == []
    one = _rows("1#", 44.0, (0.057, 0.054, 0.053), 1.6, 0.6)
    assert study_warnings(_table(one), rod_slip=2.4) == []


def test_slip_dominance_is_not_claimed_where_the_methods_stay_apart():
    """A carbon rod on a UR10 (trial): the slip 97 % of Meas's error, but None 1.209 against Meas 0.792 mm: what the
    compensation removes still shows, so no 'ranking says little'."""
    apart = _rows("cf300", 1010.0, (1.209, 0.90, 0.792), 1.8, 0.97)
    assert study_warnings(_table(apart), rod_slip=2.4) == []
    close = _rows("4#", 427.0, (0.236, 0.204, 0.204), 1.6, 0.975)
    assert [w.kind for w in study_warnings(_table(close), rod_slip=2.4)] == [StudyWarning.SLIP_DOMINATES]


def test_the_study_cli_refuses_an_absurd_slip_metres_and_lists_every_unreadable_design(tmp_path, capsys):
    from rodlab.app.cli.main import main
    assert main(["study", "rod1", "--robot", "tx90", "--rod-slip", "50", "-o", str(tmp_path / "a")]) == 2
    assert "expected 0-10" in capsys.readouterr().err
    assert main(["study", "rod1", "--L1", "0.2:0.5:0.1", "--robot", "tx90", "-o", str(tmp_path / "b")]) == 2
    assert "did you give metres" in capsys.readouterr().err
    typo = tmp_path / "t.rod.toml"
    typo.write_text('format = "rodlab.rod/1"\nname = "t"\nL1_mm = 300.0\nL2_mm = 450.0\nwal_mm = 2\n')
    assert main(["study", str(typo), "rod9", "rod1", "--robot", "tx90", "-o", str(tmp_path / "c")]) == 2
    err = capsys.readouterr().err
    assert "2 of 3 designs cannot be read" in err and "rod9" in err and "t.rod.toml" in err
    assert not (tmp_path / "a").exists() and not (tmp_path / "c").exists()


def test_a_warning_on_many_designs_is_said_once():
    """19 designs' slip warnings had pushed the study's tables a screen down (a designer trial): more than
    GROUPED_AFTER designs of one kind are one line naming how many, the first few and the range; fewer stay whole."""
    from rodlab.app.study.design_warnings import GROUPED_AFTER, DesignWarning, warning_lines
    from rodlab.core.enums import StudyWarning
    many = [DesignWarning(StudyWarning.SLIP_DOMINATES, f"D{k}", f"D{k}: long text {k}", 0.9 + 0.005 * k)
            for k in range(19)]
    few = [DesignWarning(StudyWarning.SLIP_EXTRAPOLATED, "E1", "E1: its own text", 2758.0)]
    lines = warning_lines(many + few)
    assert len(lines) == 2 and lines[1] == "E1: its own text"
    assert lines[0].startswith("19 designs (D0, D1, D2, ...)") and "90-99 %" in lines[0]
    assert warning_lines(many[:GROUPED_AFTER]) == [w.text for w in many[:GROUPED_AFTER]]


def test_the_lightest_within_ten_percent_of_the_best_mean_is_recommended_not_within_its_band():
    """A carbon rod 0.241 mm with a wide band (0.11-0.42: its r_rod prior) and a lighter aluminium one 0.353 mm
    (a designer trial: the aluminium one, 46 % worse, had been recommended for lying inside the carbon one's band;
    the designs share their draws, so that band is no measure of their difference): the carbon one; a lighter
    rod within 10 % of the best is still preferred."""
    carbon = _rows("CF40", 266.0, (0.50, 0.30, 0.241), 1.6, 0.3, mass=1.61)
    carbon[2].update(mean_p05_mm=0.112, mean_p95_mm=0.422)
    alu = _rows("AL30", 906.0, (0.90, 0.40, 0.353), 1.6, 0.9, mass=0.81)
    assert recommend(_table(carbon, alu)).design == "CF40"
    near = _rows("AL-near", 300.0, (0.90, 0.40, 0.255), 1.6, 0.9, mass=0.81)
    rec = recommend(_table(carbon, near))
    assert rec.design == "AL-near" and "within 10 % of the best one's predicted mean error" in rec.text


@pytest.mark.parametrize("option, said", [
    (["--tubes", "30x16"], "--tubes 30x16: wall 16.0 mm must be less than the outer radius"),
    (["--materials", "aluminium"], "--materials aluminium: unknown material 'aluminium'"),
    (["--tubes", "3x0.2"], "--tubes 3x0.2: outer_diameter_mm = 3: the rod would sag"),
])
def test_a_variant_option_that_makes_no_rod_is_refused_before_anything_is_written(tmp_path, capsys, option, said):
    """A new-user trial: each had run, written study.csv / .json / .html and an empty Pareto figure as "no design
    usable" and then exited 2; the tube in cm had read `ComplianceError: key C_F_mm_per_N`."""
    from rodlab.app.cli import main
    out = tmp_path / "study"
    assert main(["study", "rod1", *option, "--robot", "tx90", "-o", str(out)]) == 2
    assert said in capsys.readouterr().err and not out.exists()
