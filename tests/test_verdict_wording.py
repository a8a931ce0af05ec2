"""The calibration verdict's wording: a result that is not usable says why before its accuracy."""
from __future__ import annotations

from rodlab.app.cli import main


def test_a_result_that_is_not_usable_says_why_first(tmp_path, capsys):
    """A periodic joint error the model leaves out: usable? no names the first reason before the accuracy."""
    out = tmp_path / "pc"
    assert main(["fea", "rod1", "--model", "calc", "-o", str(tmp_path / "rod1.compliance.json")]) == 0
    assert main(["simulate-campaign", "--rod", str(tmp_path / "rod1.compliance.json"), "--effect",
                 "periodic_joint_error:joint=4", "-o", str(out)]) == 0
    capsys.readouterr()
    code = main(["calibrate", str(out / "multical.campaign.csv"), "--fixture", str(out / "multical.fixture.json"),
                 "--rod", str(tmp_path / "rod1.compliance.json")])
    usable = next(ln for ln in capsys.readouterr().out.splitlines() if "usable?" in ln)
    assert code == 3 and usable.startswith("  usable? no, because residuals") and "see NOT TRUSTED below" in usable


def test_the_short_reason_is_a_whole_clause():
    from rodlab.app.cli.verdict import _short
    assert _short("residuals (22.7 um rms) are not noise: reduced chi-square 58") == "residuals (22.7 um rms) are not noise"
    assert _short("fewer than 2 scalar readings per free parameter (too few degrees of freedom: 40 readings)") == \
        "fewer than 2 scalar readings per free parameter"
    assert _short("x" * 200).endswith("...") and len(_short("x" * 200)) == 90


def test_a_robots_error_outside_the_model_is_usable_as_validated(tmp_path, capsys):
    """The same periodic joint error with the campaign's validation points: an independent instrument shows the
    calibration predicts clearly better than the nominal model, so the residual excess is a caution, not a reason
    (a device trial: a real robot's periodic error and backlash had been NOT TRUSTED while its validation fell from
    0.572 to 0.119 mm); the reason without validation names the robot's own errors first."""
    out = tmp_path / "pc"
    rod = str(tmp_path / "rod1.compliance.json")
    assert main(["fea", "rod1", "--model", "calc", "-o", rod]) == 0
    assert main(["simulate-campaign", "--rod", rod, "--effect", "periodic_joint_error:joint=4", "-o", str(out)]) == 0
    camp, fix = str(out / "multical.campaign.csv"), str(out / "multical.fixture.json")
    capsys.readouterr()
    assert main(["calibrate", camp, "--fixture", fix, "--rod", rod]) == 3
    assert "the robot's own errors outside the model" in capsys.readouterr().err
    assert main(["calibrate", camp, "--fixture", fix, "--rod", rod, "--validate",
                 str(out / "multical.validation.csv")]) == 0
    io = capsys.readouterr()
    assert "usable? yes" in io.out and "complete? no" in io.out and "verdict: TRUSTED" in io.out
    assert "caution (trusted): the model is incomplete" in io.err and "usable at the validated accuracy" in io.err


def test_a_finding_the_validation_refutes_is_advised_for_its_kind():
    """A device trial: device axes the validation points refuted had been told to turn 'that joint' over its range."""
    from rodlab.app.diagnose.advice import remedy
    from rodlab.app.diagnose.campaign_holdout import HELD_OUT_WORSE
    from rodlab.app.diagnose.report import Finding
    device = Finding("device_axes", None, "axes", {}, {}, 1.0, 1.0, {HELD_OUT_WORSE: True})
    joint = Finding("periodic_joint_error", "joint:2", "periodic", {}, {}, 1.0, 1.0, {HELD_OUT_WORSE: True})
    assert "joint" not in remedy(device) and "reading columns' order and signs" in remedy(device)
    assert "turns that joint over its range" in remedy(joint)


def test_a_mixed_up_file_is_refused_with_a_validation_file_too(tmp_path, capsys):
    """The y_mm column negated: a validation file's clear gain must not make the excess a caution (a review: it had
    been TRUSTED at 0.099 mm against 0.036 mm with the column right); the mix-up is named."""
    out = tmp_path / "c"
    rod = str(tmp_path / "rod1.compliance.json")
    assert main(["fea", "rod1", "--model", "calc", "-o", rod]) == 0
    assert main(["simulate-campaign", "--rod", rod, "-o", str(out)]) == 0
    lines = (out / "multical.campaign.csv").read_text().splitlines()
    j = lines[0].split(",").index("y_mm")
    rows = [ln.split(",") for ln in lines[1:]]
    for r in rows:
        r[j] = f"{-float(r[j]):.4f}"
    neg = tmp_path / "neg.campaign.csv"
    neg.write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    capsys.readouterr()
    assert main(["calibrate", str(neg), "--fixture", str(out / "multical.fixture.json"), "--rod", rod, "--validate",
                 str(out / "multical.validation.csv")]) == 2        # refused, nothing written (session 49)
    err = capsys.readouterr().err
    assert "the y_mm column looks negated" in err and "usable at the validated accuracy" not in err
