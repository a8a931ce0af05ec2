"""Issue 51's done-when: a new rig effect, campaign effect, robot format or sub-command shows up in every help
text and docs table without another edit. Each kind gets a throw-away entry here, registered the way a real
one is (its module's object in the registry; monkeypatched so that nothing outlives the test), and is then
looked for in ``rodlab ... --help``, in docs/cli.md as generated and in the tables of docs/formats.md as
generated; the sub-command is a real module file, found without any other edit. The files a real one takes are
in docs/architecture.md ("Registries")."""
from __future__ import annotations

import importlib
import os
import sys
from enum import Enum
from pathlib import Path

import pytest

from rodlab.app.cli import docgen
from rodlab.calibrate.effects import CAMPAIGN_EFFECTS, CampaignEffectModel
from rodlab.calibrate.robot_formats import ROBOT_READERS, RobotFormat
from rodlab.core.hypothesis import ParamSpec
from rodlab.stiffness_rig.effects import RIG_EFFECTS, RigEffectModel

ROOT = Path(__file__).resolve().parents[1]
cli_main = importlib.import_module("rodlab.app.cli.main")      # the package's ``main`` is the function


class _New(str, Enum):
    """The IDs a real entry would add to RigEffect / CampaignEffect in rodlab/core/enums.py."""

    WOBBLE = "test_wobble"
    SAG = "test_campaign_sag"


class _Wobble(RigEffectModel):
    effect = _New.WOBBLE
    params = (ParamSpec("wobble_um", "um", "a throw-away effect's amplitude"),)
    example = {"wobble_um": 1.0}
    physics = "a throw-away rig effect of this test"
    signature = "a wobble"
    confirm = "nothing"


class _Sag(CampaignEffectModel):
    effect = _New.SAG
    params = (ParamSpec("sag_mm", "mm", "a throw-away campaign effect's size"),)
    example = {"sag_mm": 0.1}
    physics = "a throw-away campaign effect of this test"
    signature = "a sag"
    locations = ("null",)
    reported = "`sag_mm`"


#: a whole sub-command module, as a new one would be written (cmd_NAME.py beside the others)
_CMD_MODULE = '''"""``rodlab test-probe``: a throw-away sub-command of tests/test_registries_reach_docs.py."""


def register(sub) -> None:
    p = sub.add_parser("test-probe", help="a throw-away sub-command of this test",
                       description="It only shows that a module of its own reaches the help and the docs.")
    p.add_argument("--probe-level", type=int, default=1, help="how hard to probe")
    p.set_defaults(func=lambda args: 0)
'''


@pytest.fixture
def registered(monkeypatch, tmp_path):
    monkeypatch.setitem(RIG_EFFECTS, _New.WOBBLE, _Wobble())
    monkeypatch.setitem(CAMPAIGN_EFFECTS, _New.SAG, _Sag())
    monkeypatch.setitem(ROBOT_READERS, ".dhx", RobotFormat(lambda path, base, tip: None,
                                                           "a DHX test file (throw-away)", "dhx"))
    (tmp_path / "cmd_test_probe.py").write_text(_CMD_MODULE)        # the package gets one more folder to look in
    package = sys.modules["rodlab.app.cli"]
    monkeypatch.setattr(package, "__path__", [*package.__path__, str(tmp_path)])
    monkeypatch.setitem(os.environ, "COLUMNS", "200")
    yield
    sys.modules.pop("rodlab.app.cli.cmd_test_probe", None)


def _help(capsys, *argv) -> str:
    with pytest.raises(SystemExit) as e:
        cli_main.main([*argv, "--help"])
    assert e.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_each_new_entry_is_in_every_help_text(registered, capsys):
    assert "rig: friction" in _help(capsys, "diagnose") and "test_wobble" in _help(capsys, "diagnose")
    assert "test_campaign_sag" in _help(capsys, "diagnose")
    assert "test_wobble: a throw-away rig effect of this test; wobble_um [um]" in _help(capsys, "rig", "simulate")
    assert "test_campaign_sag: a throw-away campaign effect of this test; sag_mm [mm]" in \
        _help(capsys, "simulate-campaign")
    for argv in (["calibrate"], ["compare"], ["plan"], ["diagnose"], ["simulate-campaign"], ["study"]):
        assert "a DHX test file (throw-away)" in _help(capsys, *argv), argv
    assert "dhx" in _help(capsys, "validate")
    assert "test-probe" in _help(capsys) and "--probe-level" in _help(capsys, "test-probe")
    assert cli_main.main(["test-probe", "--probe-level", "2"]) == 0


def test_each_new_entry_is_in_every_generated_docs_table(registered):
    tables = docgen.render_tables((ROOT / "docs" / "formats.md").read_text(encoding="utf-8"))
    assert "| `test_wobble` | a throw-away rig effect of this test | a wobble | `null` | `wobble_um` [um] |" in tables
    assert "`test_campaign_sag`" in tables and "a throw-away campaign effect of this test" in tables
    assert "| `.dhx` | a DHX test file (throw-away) | `dhx` (its reader's rules) |" in tables
    cli = docgen.render_cli()
    assert "## `rodlab test-probe`" in cli and "a throw-away sub-command of this test" in cli
    assert "a DHX test file (throw-away)" in cli and "test_wobble" in cli and "test_campaign_sag" in cli


def test_the_sub_commands_are_the_cmd_modules_in_the_help_order():
    names = [m.__name__.rsplit(".cmd_", 1)[1] for m in cli_main.command_modules()]
    assert names == [n for n in cli_main.COMMAND_ORDER]           # every listed one exists, no stray module
    assert "sockets" not in names                                 # cmd_sockets.py (calibrate --sockets) adds none


def test_without_them_the_docs_are_what_is_committed():
    """The generated docs equal the committed ones (so the entries above would make them stale: the check of
    scripts/gen_cli_docs.py, tests/test_docs.py, fails until they are regenerated)."""
    formats = (ROOT / "docs" / "formats.md").read_text(encoding="utf-8")
    assert docgen.render_tables(formats) == formats
    assert "test_wobble" not in formats and ".dhx" not in formats
