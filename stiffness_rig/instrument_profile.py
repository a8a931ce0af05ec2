"""Rig profile ``rodlab.rigprofile/2``: the rig's instruments, each on its own port with its own protocol.

::

    format = "rodlab.rigprofile/2"

    [[instrument]]               # one per port: a gauge interface, a sensor controller, a load-cell amplifier
    name = "gauge_y"
    port = "/dev/ttyUSB0"        # a device path or a pyserial URL
    protocol = "digimatic"       # a driver of rodlab.stiffness_rig.drivers.DRIVERS
    baudrate = 9600              # also bytesize, parity, stopbits, timeout_s, retries
    request = "1\\r"              # the protocol's own settings (docs/rig.md lists them per protocol)
    [[instrument.channel]]       # what a value of this instrument measures
    quantity = "displacement"    # displacement (a tool axis), force (the load cell, along the load axis), temperature
    value = "value"              # which value of a poll (default: the protocol's first)
    axis = "y"                   # displacement only
    sign = 1.0
    scale = 1.0                  # the value times scale is in `units`
    units = "mm"                 # mm, um, in | N, kN, kgf, lbf | degC

    [loader]                     # optional: a loader commanded on one (text) instrument's port
    instrument = "gauge_y"
    command = "LOAD {axis} {phase} {mass_kg:.4f}\\r\\n"
    ack = "OK"

Version 1 profiles (one port, one line of numbers) are still read by :func:`.config.read_profile`.
"""
from __future__ import annotations

import re

from dataclasses import dataclass, field
from pathlib import Path

from .drivers import DRIVERS, SettingError
from .drivers.base import unescape
from .errors import RigError

__all__ = ["FORMAT_PROFILE_V2", "UNITS", "InstrumentChannel", "Instrument", "InstrumentProfile", "parse_profile_v2"]

FORMAT_PROFILE_V2 = "rodlab.rigprofile/2"
#: quantity -> {unit: factor to mm / N / degC}
UNITS = {"displacement": {"mm": 1.0, "um": 1e-3, "in": 25.4},
         "force": {"N": 1.0, "kN": 1e3, "daN": 10.0, "kgf": 9.80665, "lbf": 4.4482216152605, "gf": 9.80665e-3,
                   "ozf": 0.27801385095378, "mN": 1e-3},
         "temperature": {"degC": 1.0}}
_LINE_KEYS = {"name", "port", "protocol", "baudrate", "bytesize", "parity", "stopbits", "timeout_s", "retries",
              "channel"}
_CHANNEL_KEYS = {"quantity", "value", "axis", "sign", "scale", "units"}
_DEFAULT_UNITS = {"displacement": "mm", "force": "N", "temperature": "degC"}


@dataclass(frozen=True)
class InstrumentChannel:
    """One value of an instrument and what it measures.

    quantity : displacement | force | temperature; value : the driver's value name; axis : tool axis 0..2
    (displacement) or None; sign : +1 / -1; scale : the value times scale is in ``units``; units : of UNITS
    """

    quantity: str
    value: str
    axis: int | None = None
    sign: float = 1.0
    scale: float = 1.0
    units: str = "mm"

    def convert(self, v: float) -> float:
        """The instrument's value -> mm (displacement), N (force) or degC (temperature)."""
        return self.sign * self.scale * float(v) * UNITS[self.quantity][self.units]


@dataclass(frozen=True)
class Instrument:
    """One instrument on its own port: line settings, protocol and its settings (``config``), channels."""

    name: str
    port: str
    protocol: str
    config: dict
    channels: tuple
    baudrate: int = 9600
    bytesize: int = 8
    parity: str = "N"
    stopbits: float = 1.0
    timeout_s: float = 0.5
    retries: int = 5

    def driver(self):
        """A fresh driver of this instrument's protocol."""
        return DRIVERS[self.protocol](self.config)

    def identity(self) -> list:
        """What a resume checks: port, protocol and its settings, channels."""
        return [self.name, self.port, self.protocol, sorted((k, str(v)) for k, v in self.config.items()),
                [[c.quantity, c.value, c.axis, c.sign, c.scale, c.units] for c in self.channels]]


@dataclass(frozen=True)
class InstrumentProfile:
    """A rig of several instruments (``rodlab.rigprofile/2``)."""

    instruments: tuple
    loader_instrument: str | None = None
    loader_command: str | None = None
    loader_ack: str = "OK"
    path: Path | None = field(default=None, compare=False)
    format: str = FORMAT_PROFILE_V2

    @property
    def port(self) -> str:
        """Every instrument's port, joined by `` + `` (the recording's ``device``)."""
        return " + ".join(i.port for i in self.instruments)

    @property
    def protocol(self) -> str:
        return "+".join(sorted({i.protocol for i in self.instruments}))

    def channels_of(self, quantity: str) -> list:
        return [(ins, ch) for ins in self.instruments for ch in ins.channels if ch.quantity == quantity]

    @property
    def has_temperature(self) -> bool:
        return bool(self.channels_of("temperature"))

    @property
    def has_force(self) -> bool:
        return bool(self.channels_of("force"))


def _err(r, msg: str, key: str) -> RigError:
    return r.err(msg, key)


def _channel(r, ch, where: str, driver) -> InstrumentChannel:
    r.keys(ch, _CHANNEL_KEYS, where)
    q = r.string(ch, "quantity", where, choices=tuple(UNITS))
    value = ch.get("value", driver.values[0] if driver.values else "0")
    if isinstance(value, bool) or not isinstance(value, (str, int)):
        raise _err(r, f"expected the name (or place) of one of the instrument's values, got {value!r}",
                   f"{where}.value")
    value = str(value)
    if value not in driver.values:
        raise _err(r, f"the {driver.name} instrument gives the values {list(driver.values)}, not {value!r}",
                   f"{where}.value")
    axis = None
    if q == "displacement":
        axis = "xyz".index(r.string(ch, "axis", where, choices=("x", "y", "z")))
    elif "axis" in ch:
        raise _err(r, f"only a displacement has a tool axis (a {q} channel: remove `axis`)", f"{where}.axis")
    sign = r.num(ch, "sign", where, 1.0, positive=False)
    if sign not in (1.0, -1.0):
        raise _err(r, f"sign must be 1 or -1, got {sign}", f"{where}.sign")
    scale = r.num(ch, "scale", where, 1.0, positive=False)
    if scale == 0:
        raise _err(r, "scale must not be 0", f"{where}.scale")
    units = r.string(ch, "units", where, _DEFAULT_UNITS[q], tuple(UNITS[q]))
    return InstrumentChannel(q, value, axis, sign, scale, units)


#: the settings a driver writes on the line as they are (after unescaping): ASCII only
_SENT = ("request", "init", "eol")


def _ascii(text: str) -> bool:
    try:
        unescape(text).encode("ascii")
    except (UnicodeEncodeError, UnicodeDecodeError):
        return False
    return True


def _protocol_config(r, ins: dict, where: str, cls) -> dict:
    config = {}
    for s in cls.settings:
        if s.key not in ins:
            if s.default is None:
                raise _err(r, f"the {cls.name} protocol needs `{s.key}`: {s.help}", f"{where}.{s.key}")
            config[s.key] = s.default
            continue
        v = ins[s.key]
        ok = (isinstance(v, bool) if s.type is bool else
              isinstance(v, s.type) and not isinstance(v, bool) or (s.type is float and isinstance(v, int)
                                                                    and not isinstance(v, bool)))
        if not ok:
            kind = {"str": "a string", "int": "an integer", "float": "a number", "list": "a list of tables",
                    "bool": "true or false"}
            raise _err(r, f"expected {kind[s.type.__name__]}, got {v!r}", f"{where}.{s.key}")
        if s.choices and v not in s.choices:
            raise _err(r, f"expected one of {list(s.choices)}, got {v!r}", f"{where}.{s.key}")
        if s.key in _SENT and not _ascii(v):              # a review: "Rä\r" had loaded, then failed at the port
            raise _err(r, f"expected ASCII characters (what is sent on the line), got {v!r}; write other bytes as "
                          f"escapes such as \\x1b", f"{where}.{s.key}")
        config[s.key] = v
    return config


def _instrument(r, ins, k: int) -> Instrument:
    where = f"instrument[{k + 1}]"            # as the schema names it: the line is the k-th instrument's
    if not isinstance(ins, dict):
        raise _err(r, "each [[instrument]] is a table", where)
    protocol = r.string(ins, "protocol", where, choices=tuple(DRIVERS))
    cls = DRIVERS[protocol]
    r.keys(ins, _LINE_KEYS | {s.key for s in cls.settings}, where)
    name = r.string(ins, "name", where, f"instrument{k + 1}")
    config = _protocol_config(r, ins, where, cls)
    chans = ins.get("channel")
    if not isinstance(chans, list) or not chans:
        raise _err(r, f"instrument {name!r} needs at least one [[instrument.channel]] (quantity, value, axis, ...)",
                   f"{where}.channel")
    if protocol == "numeric_line" and not config.get("n_values"):
        idx = [int(c.get("value", 0)) for c in chans if isinstance(c, dict) and str(c.get("value", 0)).isdigit()]
        config["n_values"] = max(idx, default=0) + 1
    try:
        driver = cls(config)
    except SettingError as e:
        raise _err(r, f"instrument {name!r}: {e}", f"{where}.{e.key}") from e
    except re.error as e:                  # at the pattern's own line (a technician trial: it had been the [loader]'s)
        raise _err(r, f"instrument {name!r}: pattern {config.get('pattern')!r} is not a regular expression ({e}): "
                      "check its brackets and escape a literal ( ) [ ] . + * ? with a backslash", f"{where}.pattern") from e
    except Exception as e:  # noqa: BLE001 - a setting a driver refuses in its own words
        raise _err(r, f"instrument {name!r}: {e}", where) from e
    channels = tuple(_channel(r, c, f"{where}.channel[{i + 1}]", driver) for i, c in enumerate(chans))
    return Instrument(name, r.string(ins, "port", where), protocol, config, channels,
                      r.num(ins, "baudrate", where, 9600, integer=True), r.num(ins, "bytesize", where, 8, integer=True),
                      r.string(ins, "parity", where, "N", ("N", "E", "O")), r.num(ins, "stopbits", where, 1.0),
                      r.num(ins, "timeout_s", where, 0.5), r.num(ins, "retries", where, 5, integer=True))


def _check_rig(r, instruments: tuple) -> None:
    names = [i.name for i in instruments]
    if len(set(names)) != len(names):
        raise _err(r, f"instrument names must differ, got {names}", "instrument.name")
    chans = [c for i in instruments for c in i.channels]
    axes = [c.axis for c in chans if c.quantity == "displacement"]
    if not axes:
        raise _err(r, "no displacement channel: at least one gauge must read the ball", "instrument.channel")
    if len(set(axes)) != len(axes):
        raise _err(r, "two channels measure the same tool axis", "instrument.channel.axis")
    for q in ("force", "temperature"):
        if sum(c.quantity == q for c in chans) > 1:
            raise _err(r, f"more than one {q} channel; keep one", "instrument.channel.quantity")


def parse_profile_v2(data: dict, r, path) -> InstrumentProfile:
    """The ``rodlab.rigprofile/2`` table ``data`` (``r``: the reader of :mod:`.config` that names lines)."""
    r.keys(data, {"format", "instrument", "loader"}, "")
    items = data.get("instrument")
    if not isinstance(items, list) or not items:
        raise _err(r, "at least one [[instrument]] is needed (name, port, protocol, channels)", "instrument")
    instruments = tuple(_instrument(r, ins, k) for k, ins in enumerate(items))
    _check_rig(r, instruments)
    loader = data.get("loader")
    who = cmd = None
    ack = "OK"
    if loader is not None:
        r.keys(loader, {"instrument", "command", "ack"}, "loader")
        text = [i.name for i in instruments if DRIVERS[i.protocol].text_lines]
        who = r.string(loader, "instrument", "loader", text[0] if text else "")
        if who not in text:
            raise _err(r, f"the loader is commanded on a text-protocol instrument's port; one of {text}, not "
                          f"{who!r}", "loader.instrument")
        cmd = unescape(r.string(loader, "command", "loader"))
        ack = r.string(loader, "ack", "loader", "OK")
    return InstrumentProfile(instruments, who, cmd, ack, Path(path))
