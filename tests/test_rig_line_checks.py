"""A controller's line checksum over the text its pattern names, both checksums of the line protocols, and an
instrument that answers only once its ``init`` line came (remote mode): end to end on the pty simulators."""
from __future__ import annotations

import contextlib

import pytest

from rodlab.stiffness_rig import RigError
from rodlab.stiffness_rig.config import read_profile
from rodlab.stiffness_rig.drivers import Garbage
from rodlab.stiffness_rig.drivers.ascii_regex import AsciiRegex
from rodlab.stiffness_rig.protocol import encode_values, garbage_reason, line_checksum, parse_line
from rodlab.stiffness_rig import siminstruments as si
from rodlab.stiffness_rig.model import RigModel
from rodlab.stiffness_rig.siminstruments import Faults, SimBench

from test_rig_instruments import C, _check_fit, _instrument, _profile, _run

CHECKED = r"^(?P<body>M0,(?P<out1>[-+0-9.]+),(?P<out2>[-+0-9.]+))\*(?P<cs>[0-9A-Fa-f]{2})$"


def test_sum8_is_the_bytes_sum_and_numeric_lines_carry_either_checksum():
    assert line_checksum(b"AB", "sum8") == f"{(65 + 66) % 256:02X}" and line_checksum(b"AB", "xor") == "03"
    for kind in ("xor", "sum8"):
        line = encode_values([1.5, -2.25], ",", kind)
        assert parse_line(line, 2, ",", kind) == [1.5, -2.25]
        other = "sum8" if kind == "xor" else "xor"
        assert parse_line(line, 2, ",", other) is None
        assert f'set checksum = "{kind}"' in garbage_reason(line, 2, ",", other)
        assert f'set checksum = "{kind}"' in garbage_reason(line, 2, ",", "none")


class _Line:
    """A link that gives one fixed answer line."""

    def __init__(self, raw: bytes) -> None:
        self.raw = raw

    def clear_input(self) -> None:
        pass

    def write(self, data: bytes) -> None:
        pass

    def readline(self, eol: bytes = b"\n") -> bytes:
        return self.raw


def test_a_checked_controller_line_is_read_and_a_corrupted_one_is_garbage():
    body = "M0,+12.500,-3.250"
    d = AsciiRegex({"request": "M0\\r", "pattern": CHECKED, "checksum": "sum8"})
    assert d.values == ("out1", "out2")                       # body and cs are not values
    good = f"{body}*{line_checksum(body.encode(), 'sum8')}\r\n".encode()
    assert d.poll(_Line(good)) == {"out1": 12.5, "out2": -3.25}
    with pytest.raises(Garbage, match="sum8 checksum does not match"):
        d.poll(_Line(good.replace(b"12.5", b"12.6")))          # one digit changed on the line
    xor_line = f"{body}*{line_checksum(body.encode(), 'xor')}\r\n".encode()
    with pytest.raises(Garbage, match='the xor one does: set checksum = "xor"'):
        d.poll(_Line(xor_line))


def test_a_checksum_without_the_body_and_cs_groups_is_refused_at_the_pattern(tmp_path):
    body = _instrument("ctl", tmp_path / "ttyC", "ascii_regex",
                       [{"quantity": "displacement", "axis": "y", "value": "out1"}], request="M0\\r",
                       pattern=r"^M0,(?P<out1>[-+0-9.]+)\*[0-9A-F]{2}$".replace("\\", "\\\\"), checksum="xor")
    with pytest.raises(RigError) as ei:
        read_profile(_profile(tmp_path, body, None))
    assert ei.value.key == "instrument[1].pattern" and "(?P<body>" in str(ei.value) and "cs" in str(ei.value)


def test_a_checked_controller_in_remote_mode_records_the_truth_through_noise(tmp_path):
    """A controller that answers only after its remote-mode line (``init``) and ends each answer with a sum8
    checksum, on a line with 5 % garbage and a replug: the profile's simulator (made from the profile alone)
    and the acquisition agree; the fit is the rod's compliance within 1 %."""
    bench = SimBench(RigModel(C, seed=12))
    links = {"ctl": tmp_path / "ttyC"}
    body = _instrument("ctl", links["ctl"], "ascii_regex",
                       [{"quantity": "displacement", "axis": "y", "value": "out1", "units": "mm"},
                        {"quantity": "displacement", "axis": "z", "value": "out2", "units": "mm"}],
                       request="M0\\r", pattern=CHECKED.replace("\\", "\\\\"), checksum="sum8", init="R0\\r")
    profile = _profile(tmp_path, body, "ctl")
    faults = Faults(garbage=0.05, disconnect=0.01, reconnect_after_s=0.2)
    devices = si.simulators_for(read_profile(profile), bench, links, faults)
    assert devices[0].init == "R0" and not devices[0].ready
    _check_fit(_run(tmp_path, devices, profile))
    assert devices[0].initialised
    assert all(b"*" in data for _, data in devices[0].sent)


def test_without_its_init_line_the_remote_mode_simulator_stays_silent(tmp_path):
    """The simulator's side of the contract the test above relies on: no answer before ``init``."""
    bench = SimBench(RigModel(C, seed=13))
    ctl = si.SimAsciiRegex(bench, tmp_path / "ttyC", template="M0,{y_mm:+.5f},{z_mm:+.5f}", request="M0",
                           init="R0")
    assert ctl.handle(b"M0\r") == b"" and ctl.sent == []


def test_a_silent_instrument_is_not_blamed_on_an_old_garbage_line():
    """An instrument that sent one garbage line, then a good reading, then nothing: the error says 'no answer at
    all' with this reading's counts (review: the early garbage line had been shown as the cause)."""
    from rodlab.stiffness_rig.drivers import NoAnswer
    from rodlab.stiffness_rig.errors import DeviceError
    from rodlab.stiffness_rig.instrument_profile import Instrument
    from rodlab.stiffness_rig.instruments import InstrumentClient

    class Script:
        def __init__(self):
            self.calls = 0

        def after_reopen(self):
            pass

        def startup(self, link):
            pass

        def poll(self, link):
            self.calls += 1
            if self.calls == 1:
                raise Garbage(b"ERR 7", "the pattern does not match it")
            if self.calls == 2:
                return {"out1": 1.0}
            raise NoAnswer()

    ins = Instrument("ctl", "loop://", "ascii_regex", {"pattern": "^(?P<out1>.*)$"}, (), retries=2, timeout_s=0.05)
    client = InstrumentClient(ins, reconnect_attempts=1)
    client.driver = Script()
    assert client.read()[0] == {"out1": 1.0} and client.garbage == 1      # the garbage line, then the reading
    with pytest.raises(DeviceError) as ei:
        client.read()
    text = str(ei.value)
    assert "no answer at all" in text and "ERR 7" not in text and "0 garbage answers" in text


@contextlib.contextmanager
def _float32_cell(tmp_path, sent_order: str):
    """A simulated Modbus load cell on a pty sending 19.6133 N as a float32 in ``sent_order``; yields
    ``poll(word_order)``: one reading of it by a driver set to that order."""
    import serial

    from rodlab.stiffness_rig.drivers import Link
    from rodlab.stiffness_rig.drivers.modbus_rtu import ModbusRTU
    bench = SimBench(RigModel(C, seed=14, load_cell_noise_N=0.0))
    cell = si.SimModbusRTU(bench, tmp_path / "ttyF", slave=1,
                           registers={0: (lambda: 19.6133, "float32", sent_order, 3, 1.0)})
    cell.start()
    ser = serial.serial_for_url(str(cell.port), timeout=0.5)
    try:
        yield lambda order: ModbusRTU({"slave": 1, "registers": [{"name": "f", "address": 0, "type": "float32",
                                                                   "word_order": order}]}).poll(Link(ser))["f"]
    finally:
        ser.close()
        cell.stop()


def test_a_float32_load_cell_with_its_words_swapped_is_named_at_word_order(tmp_path):
    """A Modbus amplifier sending its float32 low word first to a profile that says big: each reading is
    garbage naming word_order (review: -5e32 N had been a number like any other), the right order reads the
    load cell."""
    with _float32_cell(tmp_path, "little") as poll:
        with pytest.raises(Garbage, match="set word_order to one of 'little', 'BADC', 'DCBA'"):
            poll("big")
        assert poll("little") == pytest.approx(19.6133, rel=1e-6)


def test_a_float32_load_cell_with_its_bytes_swapped_in_each_word_reads_as_BADC(tmp_path):
    """An instrument trial's load cell sent its float32 as BADC (bytes swapped within each word): no word order
    read it, and the advice to swap the words recorded 8e14 N as a force. Read as CDAB it is garbage now; as BADC
    it reads the load."""
    with _float32_cell(tmp_path, "BADC") as poll:
        with pytest.raises(Garbage, match="its four bytes in another order"):
            poll("little")                     # the advice of the old message: garbage now, not 8e14 N
        for order in ("big", "DCBA"):
            try:
                assert poll(order) != pytest.approx(19.6133, rel=0.01)
            except Garbage:
                pass
        assert poll("BADC") == pytest.approx(19.6133, rel=1e-6)


def test_a_line_in_another_separator_names_the_separator():
    assert "set separator = ';'" in garbage_reason(b"1.0;2.0;3.0\r\n", 3, ",")
    assert "set separator = '\\t'" in garbage_reason(b"1.0\t2.0\t3.0\r\n", 3, ",")
    assert "n_values = 3" in garbage_reason(b"1.0,2.0\r\n", 3, ",")          # a value short: the count


@pytest.mark.parametrize("scale, warned", [(0.01, False), (0.001, True)])
def test_a_load_cell_off_the_hung_weight_is_said_during_the_acquisition(tmp_path, caplog, scale, warned):
    """A Modbus load cell in 0.01 N counts read with the right scale, and with a scale ten times too small: the
    second is said at the first loaded hold (log and a comment in the recording), not only at the fit."""
    from test_rig_instruments import _gauges, _plan
    bench = SimBench(RigModel(C, {"friction": {"F_f_N": 0.3}}, seed=15, load_cell_noise_N=0.0))
    gauges, body = _gauges(tmp_path, bench, Faults())
    cell = si.SimModbusRTU(bench, tmp_path / "ttyF", seed=16, slave=7, registers={3: ("force_N", "int16", "big", 3,
                                                                                       100.0)})
    body += _instrument("cell", cell.port, "modbus_rtu", [{"quantity": "force", "value": "f"}], slave=7,
                        registers=[{"name": "f", "address": 3, "type": "int16", "scale": scale}])
    with caplog.at_level("WARNING"):
        _run(tmp_path, [*gauges, cell], _profile(tmp_path, body, "dial_y"), _plan(axes=("y",), masses=(1.0, 2.0)))
    text = (tmp_path / "r.rig.csv").read_text()
    assert ("# load check:" in text) == warned and ("the load cell reads" in caplog.text) == warned
    if warned:
        assert "for 1 kg" in text and text.count("# load check:") == 1       # said once, at the first loaded hold
        assert "a ratio of 0.09" in text and "look like daN" in text        # a scale 10x too small reads as daN


def test_a_non_ascii_init_line_is_refused_at_its_key(tmp_path):
    body = _instrument("ctl", tmp_path / "ttyC", "ascii_regex",
                       [{"quantity": "displacement", "axis": "y", "value": "out1"}], request="M0\\r",
                       pattern="^M0,(?P<out1>[-+0-9.]+)$", init="R\u00e4\\r")
    with pytest.raises(RigError) as ei:
        read_profile(_profile(tmp_path, body, None))
    assert ei.value.key == "instrument[1].init" and "ASCII" in str(ei.value)


def test_modbus_local_echo_is_a_setting():
    """An RS-485 adapter with its local echo on sends each request back first (an instrument trial: 'Checksum
    error' on every reading): `local_echo = true` is handed to minimalmodbus, which reads and drops the echo."""
    import serial

    from rodlab.stiffness_rig.drivers import Link
    from rodlab.stiffness_rig.drivers.modbus_rtu import ModbusRTU
    regs = [{"name": "f", "address": 0, "type": "float32"}]
    port = serial.serial_for_url("loop://", timeout=0.1)
    for echo in (True, False):
        d = ModbusRTU({"slave": 1, "registers": regs, "local_echo": echo})
        assert d._client(Link(port)).handle_local_echo is echo
    port.close()
