"""The CLI's start: a command named on the line imports and registers only its own module, and its help is
the same as from the parser of every command."""
from __future__ import annotations

import importlib
import subprocess
import sys

import pytest

cli_main = importlib.import_module("rodlab.app.cli.main")


def test_a_named_command_imports_only_its_module():
    code = ("import sys; from rodlab.app.cli.main import main; main(['info', 'rod1']); "
            "print(sorted(m for m in sys.modules if m.startswith('rodlab.app.cli.cmd_')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "['rodlab.app.cli.cmd_info']"


def _sub_help(parser, name: str) -> str:
    sub = next(a for a in parser._actions if a.dest == "command")
    return sub.choices[name].format_help()


def test_the_help_of_a_named_command_is_the_full_parsers():
    for argv in (["fea", "rod1"], ["-v", "simulate-campaign"], ["rig", "simulate"]):
        name = argv[1] if argv[0] == "-v" else argv[0]
        assert _sub_help(cli_main.build_parser(argv, every_command=False), name) == \
            _sub_help(cli_main.build_parser(), name)


def test_an_unknown_command_still_gets_the_nearest_name(capsys):
    with pytest.raises(SystemExit) as e:
        cli_main.main(["fae", "rod1"])
    assert e.value.code == 2
    assert "Did you mean `fea`?" in capsys.readouterr().err


def test_help_before_a_command_is_the_help_of_every_command(capsys):
    with pytest.raises(SystemExit):
        cli_main.main(["-h", "fea"])
    out = capsys.readouterr().out
    assert "fea" in out and "calibrate" in out and "diagnose" in out


def test_the_frame_model_does_not_bring_the_solid_fea_along():
    """rodlab.fea's names load their module on first use: the frame model (diagnose --rig's as-built fit) needs
    numpy and the core only, not scikit-fem."""
    code = ("import sys; import rodlab.fea.frame; a = 'skfem' in sys.modules; "
            "from rodlab.fea import solid_compliance; print(a, 'skfem' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True"]


def test_the_console_script_runs_main_and_leaves_its_objects_to_the_exit():
    """``rodlab`` (and ``python -m rodlab``) is ``console``: main's exit code, and the objects left frozen out
    of the collector (the exit's final collection would only walk them); pyproject names it."""
    code = ("import gc, sys; from rodlab.app.cli.main import console; sys.argv = ['rodlab', 'info', 'rod1']; "
            "rc = console(); print(rc, gc.get_freeze_count() > 1000)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip().splitlines()[-1] == "0 True"
    from source_tree import PYPROJECT
    assert PYPROJECT["project"]["scripts"]["rodlab"] == "rodlab.app.cli.main:console"
    r = subprocess.run([sys.executable, "-m", "rodlab", "info", "no-such-rod"], capture_output=True, text=True)
    assert r.returncode == 2 and "no-such-rod" in r.stderr


def test_numpy_subpackages_no_command_uses_load_only_when_used():
    """The console script defers NumPy's f2py, testing, ma ...: SciPy's array-API copy of NumPy's namespace
    no longer imports them, and each still works in full on its first use."""
    code = ("import sys; from rodlab.app.cli.startup import DEFERRED, defer_numpy_submodules\n"
            "done = defer_numpy_submodules()\n"
            "import scipy.sparse, scipy.optimize\n"
            "print(sorted(done) == sorted(DEFERRED), 'numpy.f2py.crackfortran' in sys.modules, "
            "'unittest' in sys.modules)\n"
            "import numpy as np, numpy.testing as nt\n"
            "nt.assert_allclose([1.0], [1.0]); m = np.ma.masked_array([1, 2], mask=[0, 1])\n"
            "from numpy.testing import assert_array_equal; assert_array_equal(np.char.upper(['a']), ['A'])\n"
            "print(float(m.sum()), 'unittest' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split("\n")
    assert out[0] == "True False False"
    assert out[1] == "1.0 True"
