"""A file of another kind where one kind is expected, or a number in other units, is named as that: a compliance
file given as a design, a recording given as a compliance file, a campaign given as a fixture, a recording with
no format line, a rod length in metres; an unwritable output names the user's path, never a temporary file."""
from __future__ import annotations

import pytest

from conftest import ROOT
from rodlab.app.cli import main


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("kinds")
    assert main(["fea", "rod1", "--model", "calc", "-o", str(d / "rod1.compliance.json")]) == 0
    assert main(["rig", "simulate", "--sim", "rod1", "--repeats", "1", "--hold-s", "2", "-o", str(d / "r.rig.csv")]) == 0
    assert main(["simulate-campaign", "--rod", str(d / "rod1.compliance.json"), "-o", str(d / "c")]) == 0
    return d


def _error(capsys, argv) -> str:
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return err


def test_files_of_another_kind_are_named(files, tmp_path, capsys):
    err = _error(capsys, ["fea", str(files / "rod1.compliance.json"), "--model", "calc", "-o", str(tmp_path / "x.json")])
    assert "this is a JSON file (a compliance, fixture or result file?), not the TOML file expected here" in err
    err = _error(capsys, ["rig", "fit", str(files / "r.rig.csv"), "--sim", str(files / "r.rig.csv"), "-o",
                          str(tmp_path / "x.json")])
    assert "this is a rig recording (*.rig.csv), not the JSON file expected here" in err
    c = files / "c"
    err = _error(capsys, ["calibrate", str(c / "multical.campaign.csv"), "--fixture", str(c / "multical.campaign.csv"),
                          "--rod", str(files / "rod1.compliance.json")])
    assert "this looks like a CSV table, not the JSON file expected here" in err


def test_a_recording_without_its_format_line_says_so(files, tmp_path, capsys):
    bare = tmp_path / "bare.rig.csv"
    bare.write_text("".join(ln for ln in (files / "r.rig.csv").read_text().splitlines(True)
                            if not ln.startswith("# format")))
    err = _error(capsys, ["diagnose", "--rig", str(bare), "--sim", "rod1"])
    assert "the file has none (rig acquire and rig simulate write it)" in err and "None" not in err


def test_a_rod_length_in_metres_gets_the_hint(tmp_path, capsys):
    text = (ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml").read_text()
    lines = [("L1_mm = 0.4" if ln.startswith("L1_mm") else ln) for ln in text.splitlines()]
    (tmp_path / "m.rod.toml").write_text("\n".join(lines) + "\n")
    err = _error(capsys, ["fea", str(tmp_path / "m.rod.toml"), "--model", "calc", "-o", str(tmp_path / "x.json")])
    assert "key `L1_mm`" in err and "did you give metres (0.4 m = 400 mm)?" in err


def test_an_output_folder_that_cannot_hold_files_names_the_output(tmp_path, capsys, monkeypatch):
    """The temporary file of the atomic write cannot be made (a read-only folder, /proc): the error names -o."""
    import errno

    import rodlab.core.fileio as fileio

    def refuse(prefix, suffix, dir):
        raise PermissionError(errno.EACCES, "Permission denied", f"{dir}/{prefix}abc{suffix}")
    monkeypatch.setattr(fileio.tempfile, "mkstemp", refuse)
    err = _error(capsys, ["fea", "rod1", "--model", "calc", "-o", str(tmp_path / "x.json")])
    assert f"{tmp_path / 'x.json'}:" in err and ".tmp" not in err and not (tmp_path / "x.json").exists()


def test_a_rig_only_option_with_a_campaign_is_refused(files, capsys):
    c = files / "c"
    err = _error(capsys, ["diagnose", "--campaign", str(c / "multical.campaign.csv"), "--fixture",
                          str(c / "multical.fixture.json"), "--rod", str(files / "rod1.compliance.json"),
                          "--sim-accuracy", "exact"])
    assert "--sim-accuracy" in err and "with --rig" in err
