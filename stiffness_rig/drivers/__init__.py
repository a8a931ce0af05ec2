"""Instrument protocols, one module each behind one interface (:class:`~.base.Driver`), in one registry.

Adding a protocol: a module here with a :class:`~.base.Driver` subclass (its settings, :meth:`poll`, the name of
its simulator), one line in :data:`DRIVERS`, its simulator in :mod:`..siminstruments`, one test; the profile
reader, ``rodlab validate`` and the docs table (:func:`drivers_markdown`) take it from the registry.
"""
from __future__ import annotations

from .ascii_regex import AsciiRegex
from .base import Driver, Garbage, Link, NoAnswer, Setting, SettingError
from .digimatic import Digimatic
from .modbus_rtu import ModbusRTU
from .numeric_line import NumericLine

__all__ = ["DRIVERS", "Driver", "Garbage", "Link", "NoAnswer", "Setting", "SettingError", "driver_class",
           "drivers_markdown"]

#: protocol name -> driver class
DRIVERS: dict[str, type[Driver]] = {d.name: d for d in (NumericLine, AsciiRegex, Digimatic, ModbusRTU)}


def driver_class(name: str) -> type[Driver]:
    """The driver of protocol ``name``; KeyError naming the known ones."""
    if name not in DRIVERS:
        raise KeyError(f"unknown protocol {name!r}; known: {sorted(DRIVERS)}")
    return DRIVERS[name]


def drivers_markdown() -> str:
    """The table of protocols and their settings for docs/rig.md."""
    rows = ["| protocol | what it talks to | settings (default) |", "|---|---|---|"]
    for d in DRIVERS.values():
        sets = "; ".join(f"`{s.key}` ({'required' if s.default is None else repr(s.default)}): {s.help}"
                         for s in d.settings)
        rows.append(f"| `{d.name}` | {d.summary} | {sets} |")
    return "\n".join(rows)
