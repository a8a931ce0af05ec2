"""Issue 51's done-when: a new rig effect, campaign effect, compensation, robot format or sub-command is one
module (plus its test) and shows up in every help text and docs table without another edit. Each throw-away
entry here is a real module file, written into a folder added to its package's ``__path__`` and found by the
package's discovery (monkeypatched, and rediscovered without them after the test, so that nothing outlives it).
Each is then looked for in ``rodlab ... --help``, in docs/cli.md as generated and in the generated tables of
docs/formats.md and docs/calibrate.md; the effects also in their Enum, and each is shown to work: the
simulators apply the effects and the compensation, ``read_robot`` reads the new format. The files a real one
takes are in docs/architecture.md ("Registries")."""
from __future__ import annotations

import csv
import importlib
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli import docgen
from rodlab.app.diagnose.effect_ids import parse_effect_id
from rodlab.calibrate import compensations, read_robot, resolve_robot, robot_formats
from rodlab.calibrate import effects as campaign_effects
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab.core.compliance import read_compliance
from rodlab.core.errors import RodlabError
from rodlab.stiffness_rig import effects as rig_effects

ROOT = Path(__file__).resolve().parents[1]
cli_main = importlib.import_module("rodlab.app.cli.main")      # the package's ``main`` is the function

#: a whole rig effect module, as a new one would be written (stiffness_rig/effects/NAME.py beside the others):
#: the gauges drift by rate_um_per_s on every axis (from the start of the recording)
_RIG_MODULE = '''"""``test_wobble``: a throw-away rig effect of tests/test_registries_reach_docs.py."""
import numpy as np

from rodlab.core.hypothesis import ParamSpec
from rodlab.stiffness_rig.effects.base import RigEffectModel


class Wobble(RigEffectModel):
    effect = "test_wobble"
    order = 1000
    params = (ParamSpec("rate_um_per_s", "um/s", "a throw-away effect's rate"),)
    example = {"rate_um_per_s": 1.0}
    physics = "a throw-away rig effect of this test"
    signature = "a wobble"
    confirm = "nothing"

    def reading(self, x, t, dtemp_K, p):
        return x + 1e-3 * self.value(p, "rate_um_per_s") * t * np.ones(3)
'''

#: a whole campaign effect module (calibrate/effects/NAME.py): every measured ball centre sags by sag_mm in {W}
_CAMPAIGN_MODULE = '''"""``test_campaign_sag``: a throw-away campaign effect of tests/test_registries_reach_docs.py."""
import numpy as np

from rodlab.calibrate.effects.base import CampaignEffectModel
from rodlab.core.hypothesis import ParamSpec


class Sag(CampaignEffectModel):
    effect = "test_campaign_sag"
    order = 1000
    params = (ParamSpec("sag_mm", "mm", "a throw-away campaign effect's size"),)
    example = {"sag_mm": 0.1}
    physics = "a throw-away campaign effect of this test"
    signature = "a sag"
    locations = ("null",)
    reported = "`sag_mm`"

    def reading_offset_W(self, frames, time_s, p):
        return np.broadcast_to([0.0, 0.0, -float(p["sag_mm"])], (len(time_s), 3))
'''

#: a whole compensation module (calibrate/compensations/NAME.py): the ball centre sits shift_mm higher in {W}
_COMPENSATION_MODULE = '''"""``test_shift``: a throw-away compensation of tests/test_registries_reach_docs.py."""
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rodlab.calibrate.compensations.base import Compensation


@dataclass(frozen=True)
class Shift(Compensation):
    name: ClassVar[str] = "test_shift"
    summary: ClassVar[str] = "a throw-away compensation of this test"
    needs: ClassVar[str] = "nothing"
    option: ClassVar[str] = "`--test-shift`"
    shift_mm: float = 0.2
    label: str = "shift"

    def offsets(self, robot, params, at):
        return np.tile([0.0, 0.0, self.shift_mm], (np.atleast_2d(at.q_rad).shape[0], 1))
'''

#: a whole robot reader module (calibrate/robot_NAME.py): a .dhx file names a built-in robot
_ROBOT_MODULE = '''"""``.dhx`` robot files: a throw-away robot format of tests/test_registries_reach_docs.py."""
from pathlib import Path

from rodlab.calibrate.robot_formats import resolve_robot
from rodlab.calibrate.robot_reader import RobotFormat


def _read(path, base_link=None, tip_link=None):
    return resolve_robot(Path(path).read_text().strip())


ROBOT_FORMAT = RobotFormat(_read, "a DHX test file (throw-away)", "dhx", suffix=".dhx")
'''

#: a whole sub-command module, as a new one would be written (cmd_NAME.py beside the others)
_CMD_MODULE = '''"""``rodlab test-probe``: a throw-away sub-command of tests/test_registries_reach_docs.py."""


def register(sub) -> None:
    p = sub.add_parser("test-probe", help="a throw-away sub-command of this test",
                       description="It only shows that a module of its own reaches the help and the docs.")
    p.add_argument("--probe-level", type=int, default=1, help="how hard to probe")
    p.set_defaults(func=lambda args: 0)
'''


def _add_module(monkeypatch, package, folder: Path, name: str, text: str) -> None:
    """``name``.py with ``text`` in ``folder``, which the ``package`` gets as one more folder to look in."""
    folder.mkdir()
    (folder / f"{name}.py").write_text(text)
    monkeypatch.setattr(package, "__path__", [*package.__path__, str(folder)])


@pytest.fixture
def registered(monkeypatch, tmp_path):
    before = (rig_effects.RigEffect, dict(rig_effects.RIG_EFFECTS), campaign_effects.CampaignEffect,
              dict(campaign_effects.CAMPAIGN_EFFECTS))
    _add_module(monkeypatch, rig_effects, tmp_path / "rig", "test_wobble", _RIG_MODULE)
    _add_module(monkeypatch, campaign_effects, tmp_path / "campaign", "test_campaign_sag", _CAMPAIGN_MODULE)
    _add_module(monkeypatch, compensations, tmp_path / "compensation", "test_shift", _COMPENSATION_MODULE)
    _add_module(monkeypatch, sys.modules["rodlab.calibrate"], tmp_path / "robot", "robot_test_dhx", _ROBOT_MODULE)
    _add_module(monkeypatch, sys.modules["rodlab.app.cli"], tmp_path / "cli", "cmd_test_probe", _CMD_MODULE)
    _rediscover()
    monkeypatch.setitem(os.environ, "COLUMNS", "200")
    yield tmp_path
    monkeypatch.undo()
    for name in ("rodlab.app.cli.cmd_test_probe", "rodlab.stiffness_rig.effects.test_wobble",
                 "rodlab.calibrate.effects.test_campaign_sag", "rodlab.calibrate.compensations.test_shift",
                 "rodlab.calibrate.robot_test_dhx"):
        sys.modules.pop(name, None)
    _rediscover()
    assert ".dhx" not in robot_formats.ROBOT_READERS and "test_shift" not in compensations.COMPENSATIONS
    after = (rig_effects.RigEffect, rig_effects.RIG_EFFECTS, campaign_effects.CampaignEffect,
             campaign_effects.CAMPAIGN_EFFECTS)
    assert all(a is b or a == b for a, b in zip(before, after)), "the rediscovery did not give the registries back"
    assert all(m.effect in before[0] for m in before[1].values())


def _rediscover() -> None:
    """Every registry that finds its modules, found again (sub-commands are found whenever the parser is built)."""
    for package in (rig_effects, campaign_effects, compensations, robot_formats):
        package.discover()


def _help(capsys, *argv) -> str:
    with pytest.raises(SystemExit) as e:
        cli_main.main([*argv, "--help"])
    assert e.value.code == 0
    return " ".join(capsys.readouterr().out.split())


def test_each_new_entry_is_in_every_help_text(registered, capsys):
    assert "rig: friction" in _help(capsys, "diagnose") and "test_wobble" in _help(capsys, "diagnose")
    assert "test_campaign_sag" in _help(capsys, "diagnose")
    assert "test_wobble: a throw-away rig effect of this test; rate_um_per_s [um/s]" in \
        _help(capsys, "rig", "simulate")
    assert "test_campaign_sag: a throw-away campaign effect of this test; sag_mm [mm]" in \
        _help(capsys, "simulate-campaign")
    for argv in (["calibrate"], ["compare"], ["plan"], ["diagnose"], ["simulate-campaign"], ["study"]):
        assert "a DHX test file (throw-away)" in _help(capsys, *argv), argv
    assert "dhx" in _help(capsys, "validate")
    assert "test_shift: --test-shift" in _help(capsys, "calibrate")
    assert "test-probe" in _help(capsys) and "--probe-level" in _help(capsys, "test-probe")
    assert cli_main.main(["test-probe", "--probe-level", "2"]) == 0


def test_each_new_entry_is_in_every_generated_docs_table(registered):
    tables = docgen.render_tables((ROOT / "docs" / "formats.md").read_text(encoding="utf-8"))
    assert ("| `test_wobble` | a throw-away rig effect of this test | a wobble | `null` | `rate_um_per_s` [um/s] |"
            in tables)
    assert "`test_campaign_sag`" in tables and "a throw-away campaign effect of this test" in tables
    assert "| `.dhx` | a DHX test file (throw-away) | `dhx` (its reader's rules) |" in tables
    page = (ROOT / "docs" / "calibrate.md").read_text(encoding="utf-8")
    assert ("| `test_shift` | a throw-away compensation of this test | nothing | `--test-shift` |"
            in docgen.render_tables(page, docgen.DOC_TABLES["calibrate.md"]))
    cli = docgen.render_cli()
    assert "## `rodlab test-probe`" in cli and "a throw-away sub-command of this test" in cli
    assert "a DHX test file (throw-away)" in cli and "test_wobble" in cli and "test_campaign_sag" in cli
    assert "test_shift" in cli


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


def test_each_new_effect_is_in_its_enum_and_its_registry_in_order(registered):
    assert rig_effects.RigEffect.TEST_WOBBLE == "test_wobble" == rig_effects.RigEffect.parse("Test_Wobble")
    assert list(rig_effects.RIG_EFFECTS)[-1] is rig_effects.RigEffect("test_wobble")
    assert rig_effects.rig_effect("friction").effect is rig_effects.RigEffect.FRICTION     # the others stay
    assert [e.value for e in rig_effects.RigEffect][:2] == ["friction", "tare"]
    sag = campaign_effects.CampaignEffect.TEST_CAMPAIGN_SAG
    assert list(campaign_effects.CAMPAIGN_EFFECTS)[-1] is sag and campaign_effects.campaign_effect(sag.value).effect is sag
    assert parse_effect_id("test_wobble") is rig_effects.RigEffect.TEST_WOBBLE and parse_effect_id(sag.value) is sag


def _rows(path: Path) -> list[dict]:
    """The rows of a CSV after its ``#`` comment lines."""
    return list(csv.DictReader(line for line in path.read_text().splitlines() if not line.startswith("#")))


def _read_csv(path: Path, *cols: str) -> np.ndarray:
    """The columns ``cols`` of a CSV, as floats (an empty cell: NaN)."""
    return np.array([[float(r[c] or "nan") for c in cols] for r in _rows(path)])


def test_the_simulators_apply_each_new_effect(registered):
    """``rodlab rig simulate --effect test_wobble`` drifts by rate_um_per_s from the zeroing at the start of each
    series (the gauges are zeroed when the rod is remounted for another load axis); ``rodlab
    simulate-campaign --effect test_campaign_sag`` moves every measured ball centre by sag_mm (rotated into the
    device frame: the distance is kept) and records the effect in truth.json."""
    out = registered
    rig = ["rig", "simulate", "--sim", "rod1", "--masses", "1", "--axes", "z,x", "--repeats", "1", "--noise-um", "0"]
    assert cli_main.main([*rig, "-o", str(out / "plain.rig.csv")]) == 0
    assert cli_main.main([*rig, "--effect", "test_wobble:rate_um_per_s=2", "-o", str(out / "wobble.rig.csv")]) == 0
    cols = ("time_s", "disp_x_mm", "disp_z_mm")
    plain, wobble = _read_csv(out / "plain.rig.csv", *cols), _read_csv(out / "wobble.rig.csv", *cols)
    axis = [r["load_axis"] for r in _rows(out / "plain.rig.csv")]
    t_zero = np.array([plain[axis.index(a), 0] for a in axis])          # each series' first sample
    drift = 2e-3 * (plain[:, 0] - t_zero)
    measured = np.isfinite(plain[:, 1:])
    assert measured.sum() > 100 and drift.max() > 0.05
    assert np.allclose((wobble[:, 1:] - plain[:, 1:])[measured], np.repeat(drift[:, None], 2, 1)[measured],
                       atol=1.01e-3)                                     # each reading rounded to 1 um

    assert cli_main.main(["compliance", "rod1", "-o", str(out / "rod1.compliance.json")]) == 0
    camp = ["simulate-campaign", "--robot", "tx90", "--rod", str(out / "rod1.compliance.json"), "--positions", "2",
            "--orientations", "4", "--noise-um", "0"]
    assert cli_main.main([*camp, "-o", str(out / "plain")]) == 0
    assert cli_main.main([*camp, "--effect", "test_campaign_sag:sag_mm=0.5", "-o", str(out / "sag")]) == 0
    xyz = ("x_mm", "y_mm", "z_mm")
    moved = _read_csv(out / "sag" / "multical.campaign.csv", *xyz) - _read_csv(out / "plain" / "multical.campaign.csv",
                                                                                *xyz)
    assert np.allclose(np.linalg.norm(moved, axis=1), 0.5, atol=2e-4)
    truth = json.loads((out / "sag" / "truth.json").read_text())
    assert truth["effects"] == [{"effect": "test_campaign_sag", "sag_mm": 0.5}]


def test_the_campaign_simulator_applies_the_new_compensation(registered):
    """``simulate_campaign(compensations=[...])`` with the new module's class moves every reading by its offset."""
    shift = compensations.COMPENSATIONS["test_shift"](shift_mm=0.2)
    assert cli_main.main(["compliance", "rod1", "-o", str(registered / "rod1.compliance.json")]) == 0
    rod = read_compliance(registered / "rod1.compliance.json")
    spec = CampaignSpec(positions=2, orientations=4, device_noise_mm=0.0)
    robot = resolve_robot("tx90")
    simulate_campaign(robot, rod, registered / "plain", spec)
    simulate_campaign(robot, rod, registered / "shift", spec, compensations=[shift])
    xyz = ("x_mm", "y_mm", "z_mm")
    moved = (_read_csv(registered / "shift" / "multical.campaign.csv", *xyz)
             - _read_csv(registered / "plain" / "multical.campaign.csv", *xyz))
    assert np.allclose(np.linalg.norm(moved, axis=1), 0.2, atol=2e-4)


def test_read_robot_reads_the_new_format(registered):
    (registered / "arm.dhx").write_text("ur5\n")
    robot = read_robot(registered / "arm.dhx")
    assert robot.n == resolve_robot("ur5").n and np.allclose(robot.a_mm, resolve_robot("ur5").a_mm)


@pytest.mark.parametrize("edit, message", [
    (('"test_wobble"', '"friction"'), r"rig effects \S+\.friction and \S+\.test_clash both have the ID 'friction'"),
    (("order = 1000", "order = 70"), r"rig effects \S+\.creep and \S+\.test_clash both have the order 70"),
    (("    order = 1000\n", ""), r"rig effect test_wobble \(\S+\.test_clash\.Wobble\) declares no `order = N`")])
def test_a_module_that_clashes_is_refused_naming_it(monkeypatch, tmp_path, edit, message):
    """Two effects with one ID or one place, or one without a place: the discovery names the modules, and the
    registry stays as it was."""
    before = dict(rig_effects.RIG_EFFECTS)
    _add_module(monkeypatch, rig_effects, tmp_path / "rig", "test_clash", _RIG_MODULE.replace(*edit))
    try:
        with pytest.raises(RodlabError, match=message):
            rig_effects.discover()
    finally:
        sys.modules.pop("rodlab.stiffness_rig.effects.test_clash", None)
    assert rig_effects.RIG_EFFECTS == before
