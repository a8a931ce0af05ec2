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
