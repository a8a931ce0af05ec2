"""A technician connecting their own instruments (2026-11-29, helper-55): every wired gauge recorded unless the plan
says otherwise, unreadable answers shown with their reason, profile errors at their own line, a swapped Modbus word
order named, a plan that cannot be fitted refused."""
from __future__ import annotations

from rodlab.app.cli import main
from rodlab.stiffness_rig.config import RigPlan, read_plan
from rodlab.stiffness_rig.drivers.base import Garbage
from rodlab.stiffness_rig.fit_checks import scale_cause
from rodlab.stiffness_rig.model import LoadSchedule
from rodlab.stiffness_rig.protocol import garbage_reason, xor_checksum

_PLAN = """format = "rodlab.rigplan/1"
rod = "1#"
axes = ["y", "z"]
masses_kg = {masses}
repeats = {repeats}
hold_s = 1.0
rate_Hz = 20.0
{measured}"""


def test_a_series_records_every_gauge_unless_the_plan_lists_them(tmp_path):
    """The schedule's default x and z under a z load had blanked a wired y gauge."""
    path = tmp_path / "p.plan.toml"
    path.write_text(_PLAN.format(masses="[0.5, 1.0]", repeats=2, measured=""))
    assert read_plan(path).recorded("z") == (0, 1, 2)
    path.write_text(_PLAN.format(masses="[0.5, 1.0]", repeats=2, measured='[measured]\nz = ["x", "z"]\n'))
    plan = read_plan(path)
    assert plan.recorded("z") == (0, 2) and plan.recorded("y") == (0, 1, 2)
    assert RigPlan("1#", LoadSchedule()).recorded("x") == (0, 1, 2)


def test_a_plan_the_fit_cannot_use_is_refused(tmp_path, capsys):
    path = tmp_path / "tiny.plan.toml"
    path.write_text(_PLAN.format(masses="[0.5]", repeats=1, measured=""))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "line 5, key `repeats`" in err and "add a mass or a repeat" in err


def test_an_unreadable_answer_says_why():
    line = b"-0.05570;0.1*" + xor_checksum(b"-0.05570;0.1").encode() + b"\r\n"
    assert "set checksum = \"xor\"" in garbage_reason(line, 2, ";", "none")
    assert "2 value(s)" in garbage_reason(b"1.0;2.0\r\n", 1, ";", "none")
    assert "no '*HH' checksum" in garbage_reason(b"1.0\r\n", 1, ",", "xor")
    assert "received b'+00.1234 um'" in str(Garbage(b"+00.1234 um", "the pattern does not match it"))


def test_profile_errors_are_at_their_own_line(tmp_path, capsys):
    head = ('format = "rodlab.rigprofile/2"\n\n[[instrument]]\nname = "g"\nport = "/tmp/nowhere"\n'
            'protocol = "ascii_regex"\n')
    bad_regex = tmp_path / "r.profile.toml"
    bad_regex.write_text(head + "pattern = '^(?P<d>[-+0-9.]+ mm$'\n\n[[instrument.channel]]\nquantity = "
                         '"displacement"\nvalue = "d"\naxis = "y"\n')
    assert main(["validate", str(bad_regex)]) == 2
    err = capsys.readouterr().err
    assert "line 7, key `instrument[1].pattern`" in err and "is not a regular expression" in err
    misspelt = tmp_path / "c.profile.toml"
    misspelt.write_text(head + "pattern = '^(?P<d>[-+0-9.]+) mm$'\n\n[[instrument.chanel]]\nquantity = "
                        '"displacement"\nvalue = "d"\naxis = "y"\n')
    assert main(["validate", str(misspelt)]) == 2
    err = capsys.readouterr().err
    assert "line 9" in err and "rename `chanel` to `channel`" in err


def test_a_swapped_modbus_word_order_is_named():
    cause, fix = scale_cause(65550.0, "y")
    assert "16-bit Modbus registers" in cause and "word_order" in fix
