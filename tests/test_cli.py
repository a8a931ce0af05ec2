"""The rodlab CLI: sub-commands work and bad input is one clear line, never a traceback."""
from __future__ import annotations

import json

import pytest
import subprocess
import sys

from rodlab.app.cli import main


def test_help_lists_subcommands(capsys):
    try:
        main(["--help"])
    except SystemExit as e:
        assert e.code == 0
    out = capsys.readouterr().out
    for cmd in ("info", "compliance"):
        assert cmd in out


def test_info_and_compliance(tmp_path, capsys):
    assert main(["info", "rod1"]) == 0
    out = capsys.readouterr().out
    assert "total mass" in out and "c_rod" in out and "ball_holder" in out
    assert "cfrp_tube" in out and "kg/m^3" in out                # every material's numbers (a designer trial)
    assert main(["info", "rod2", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["design"]["L1_mm"] == 150.0
    steel = data["materials"]["steel_304"]
    assert steel["G_GPa"] == pytest.approx(steel["E_GPa"] / (2 * (1 + steel["nu"])))     # derived where not given
    out_file = tmp_path / "r.compliance.json"
    assert main(["compliance", "rod1", "-o", str(out_file)]) == 0
    assert json.loads(out_file.read_text())["method"] == "calc"
    assert main(["compliance", "rod1", "--method", "none", "-o", str(tmp_path / "n.json")]) == 0
    assert json.loads((tmp_path / "n.json").read_text())["C_F_mm_per_N"][1][1] == 0.0


def test_bad_input_is_one_line(tmp_path):
    bad = tmp_path / "bad.rod.toml"
    bad.write_text('format = "rodlab.rod/1"\nL1_mm = 300\nL2_mm = 450\ngamma_deg = 90\n'
                   '[tube]\nmaterial = "cfrp"\nouter_diameter_mm = 25\nwal_mm = 2\n')
    r = subprocess.run([sys.executable, "-m", "rodlab", "info", str(bad)], capture_output=True, text=True)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "line 8" in r.stderr and "Did you mean `wall_mm`?" in r.stderr
    r = subprocess.run([sys.executable, "-m", "rodlab", "info", str(tmp_path / "none.rod.toml")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "not found" in r.stderr and "Traceback" not in r.stderr


def _exit_code(argv) -> int:
    """main's return code, or argparse's exit code when it refuses an argument."""
    try:
        return main(argv)
    except SystemExit as e:
        return int(e.code)


def test_bad_rig_simulation_options_name_the_option_and_leave_no_file(tmp_path_factory, capsys):
    """Negative noise, a negative or unordered mass, no repeats: exit 2 with the option named, nothing written
    (the recording is written whole, then renamed); an existing recording is kept."""
    sim = tmp_path_factory.mktemp("sim") / "rod1.compliance.json"
    assert main(["compliance", "rod1", "-o", str(sim)]) == 0
    tmp_path = tmp_path_factory.mktemp("out")
    out = tmp_path / "rec.rig.csv"
    for bad, key in [(["--noise-um", "-3"], "noise"), (["--masses=-1,2"], "masses"), (["--masses=2,1"], "masses"),
                     (["--repeats", "0"], "repeats"), (["--rate-hz", "0"], "rate-hz")]:
        code = _exit_code(["rig", "simulate", "--sim", str(sim), *bad, "-o", str(out)])
        err = capsys.readouterr().err
        assert code == 2 and key in err and "Traceback" not in err, (bad, err)
        assert not out.exists() and not list(tmp_path.iterdir()), bad
    assert main(["rig", "simulate", "--sim", str(sim), "--repeats", "1", "-o", str(out)]) == 0
    before = out.read_bytes()
    assert _exit_code(["rig", "simulate", "--sim", str(sim), "--noise-um", "-1", "-o", str(out)]) == 2
    assert out.read_bytes() == before and sorted(p.name for p in tmp_path.iterdir()) == ["rec.rig.csv"]


def test_builtin_robot_names_are_case_blind_and_options_work_after_the_subcommand(tmp_path, capsys):
    from rodlab.calibrate import resolve_robot
    assert resolve_robot("TX90").n == resolve_robot("tx90").n == 6
    from rodlab.app.cli.main import build_parser
    args = build_parser().parse_args(["rig", "simulate", "--sim", "rod1", "-o", "x.csv", "--debug", "-q"])
    assert args.debug and args.quiet
    args = build_parser().parse_args(["--debug", "fea", "rod1", "-o", "x.json"])
    assert args.debug and not args.quiet
