"""``modbus_rtu``: a load-cell amplifier or transmitter speaking Modbus RTU: holding (function 3) or input
(function 4) registers as int16 / uint16 / int32 / uint32 / float32 (two registers, word order ``big`` =
high word first, ``little`` = low word first), each times its ``scale``. Through minimalmodbus, on the instrument's own
pyserial port (so pyserial URLs work too). Measured against pymodbus 3.16 on the pty simulator (this machine,
2 shared cores): a float32 read 2.2 ms median against 5.2-5.6 ms, the import 5-25 ms against 66-200 ms, one
132 kB pure-Python module on pyserial against a 1.4 MB package with asyncio underneath: minimalmodbus."""
from __future__ import annotations

import math

import minimalmodbus

from .base import Driver, Garbage, Link, NoAnswer, Setting, SettingError

__all__ = ["ModbusRTU", "REGISTER_TYPES"]

#: register type -> number of 16-bit registers
REGISTER_TYPES = {"int16": 1, "uint16": 1, "int32": 2, "uint32": 2, "float32": 2}
_REGISTER_KEYS = {"name", "address", "function", "type", "word_order", "scale"}


def _register(entry, k: int) -> dict:
    where = f"registers[{k}]"
    if not isinstance(entry, dict):
        raise SettingError(where, "expected a table {name, address, function, type, word_order, scale}")
    extra = set(entry) - _REGISTER_KEYS
    if extra:
        raise SettingError(f"{where}.{sorted(extra)[0]}", f"unknown key; allowed: {sorted(_REGISTER_KEYS)}")
    reg = {"name": entry.get("name"), "address": entry.get("address"), "function": entry.get("function", 3),
           "type": entry.get("type", "int16"), "word_order": entry.get("word_order", "big"),
           "scale": entry.get("scale", 1.0)}
    if not isinstance(reg["name"], str) or not reg["name"]:
        raise SettingError(f"{where}.name", "each register needs a name (a channel's value)")
    if isinstance(reg["address"], bool) or not isinstance(reg["address"], int) or not 0 <= reg["address"] <= 65535:
        raise SettingError(f"{where}.address", f"expected a register address 0..65535, got {reg['address']!r}")
    if reg["function"] not in (3, 4):
        raise SettingError(f"{where}.function", f"expected 3 (holding) or 4 (input), got {reg['function']!r}")
    if reg["type"] not in REGISTER_TYPES:
        raise SettingError(f"{where}.type", f"expected one of {sorted(REGISTER_TYPES)}, got {reg['type']!r}")
    if reg["word_order"] not in WORD_ORDERS:
        raise SettingError(f"{where}.word_order", f"expected one of {', '.join(WORD_ORDERS)}, got "
                                                  f"{reg['word_order']!r}")
    s = reg["scale"]
    if isinstance(s, bool) or not isinstance(s, (int, float)) or not math.isfinite(s) or s == 0:
        raise SettingError(f"{where}.scale", f"expected a finite non-zero number, got {s!r}")
    return reg


#: the order of a 32-bit value's four bytes over its two registers, A the most significant: ``big`` (ABCD) and
#: ``little`` (CDAB, the words swapped) as most instruments, BADC and DCBA (bytes swapped within each word: an
#: instrument trial's load cell) by their letters; minimalmodbus's constant for each
WORD_ORDERS = {"big": 0, "little": 3, "ABCD": 0, "CDAB": 3, "BADC": 2, "DCBA": 1}
#: the magnitudes a float32 register of an instrument can hold; its bytes in another order give ~1e-30 or ~1e30,
#: and often 1e11-1e15 (an instrument trial's BADC load cell read as CDAB: 8e14 N had passed a bound of 1e15)
FLOAT32_PLAUSIBLE = (1e-15, 1e10)


def _check_float(v: float, reg: dict) -> None:
    """Garbage naming ``word_order`` for a float32 no instrument reads (review: a load cell's float32 with its
    words swapped reads ~-5e32 N)."""
    if v != 0.0 and math.isfinite(v) and not FLOAT32_PLAUSIBLE[0] <= abs(v) <= FLOAT32_PLAUSIBLE[1]:
        other = [o for o in ("big", "little", "BADC", "DCBA") if WORD_ORDERS[o] != WORD_ORDERS[reg["word_order"]]]
        raise Garbage(b"", f"register {reg['name']} reads {v:.3g}, no instrument's value: its four bytes in another "
                           f"order? set word_order to one of {', '.join(repr(o) for o in other)} (the instrument's "
                           "manual names it: ABCD = big, CDAB = little)")


class ModbusRTU(Driver):
    name = "modbus_rtu"
    summary = "Modbus RTU holding / input registers (int16/32, float32, byte order, scale) via minimalmodbus"
    settings = (Setting("slave", int, 1, "the instrument's Modbus address (1..247)"),
                Setting("registers", list, None, "[[instrument.registers]] tables: name, address, function (3 "
                                                 "holding, 4 input), type (int16, uint16, int32, uint32, float32), "
                                                 "word_order (big = ABCD, little = CDAB, BADC, DCBA), scale"),
                Setting("local_echo", bool, False, "true where the RS-485 adapter echoes each request back (its "
                                                   "local echo on): the echo is read and dropped"))
    simulator = "SimModbusRTU"
    text_lines = False

    def __init__(self, config: dict) -> None:
        super().__init__(config)
        regs = config.get("registers")
        if not isinstance(regs, list) or not regs:
            raise SettingError("registers", "at least one register is needed")
        self.registers = [_register(e, k) for k, e in enumerate(regs)]
        names = [r["name"] for r in self.registers]
        if len(set(names)) != len(names):
            raise SettingError("registers", f"register names must differ, got {names}")
        slave = config.get("slave", 1)
        if isinstance(slave, bool) or not isinstance(slave, int) or not 1 <= slave <= 247:
            raise SettingError("slave", f"expected a Modbus address 1..247, got {slave!r}")
        self._instrument = None
        self._serial = None

    @property
    def values(self) -> tuple:
        return tuple(r["name"] for r in self.registers)

    def after_reopen(self) -> None:
        self._instrument = self._serial = None

    def _client(self, link: Link):
        if self._instrument is None or self._serial is not link.serial:
            self._instrument = minimalmodbus.Instrument(link.serial, int(self.config.get("slave", 1)))
            self._instrument.clear_buffers_before_each_transaction = True
            self._instrument.handle_local_echo = bool(self.config.get("local_echo", False))
            self._serial = link.serial
        return self._instrument

    def _read(self, inst, reg: dict) -> float:
        order = WORD_ORDERS[reg["word_order"]]
        t, fc, a = reg["type"], reg["function"], reg["address"]
        if t in ("int16", "uint16"):
            v = inst.read_register(a, 0, fc, signed=t == "int16")
        elif t in ("int32", "uint32"):
            v = inst.read_long(a, fc, signed=t == "int32", byteorder=order)
        else:
            v = inst.read_float(a, fc, 2, byteorder=order)
            _check_float(float(v), reg)
        return float(v) * float(reg["scale"])

    def poll(self, link: Link) -> dict:
        inst = self._client(link)
        out = {}
        for reg in self.registers:
            try:
                v = self._read(inst, reg)
            except minimalmodbus.NoResponseError as e:
                raise NoAnswer(str(e)) from e
            except (minimalmodbus.ModbusException, ValueError) as e:       # CRC, wrong slave / length, an exception code
                raise Garbage(b"", f"{type(e).__name__}: {e}") from e
            if not math.isfinite(v):
                raise Garbage(b"", f"register {reg['name']} is not finite")
            out[reg["name"]] = v
        return out
