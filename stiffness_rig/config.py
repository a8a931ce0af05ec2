"""Rig profiles (how the instruments are wired) and acquisition plans (what to record), TOML files.

Profile (``rodlab.rigprofile/1``)::

    format = "rodlab.rigprofile/1"
    [device]
    port = "/dev/ttyUSB0"        # a device path or a pyserial URL (socket://host:port, rfc2217://..., loop://)
    baudrate = 9600              # also: bytesize = 8, parity = "N" | "E" | "O", stopbits = 1, timeout_s = 0.5
    protocol = "query"           # "query": request / one-line answer; "stream": the device pushes lines
    request = "R\\r\\n"            # query only: what asks for a reading
    separator = ","              # between channel values in a line
    checksum = "none"            # "none" | "xor" | "sum8" (line ends with *HH over the bytes before '*')
    retries = 5                  # attempts before the device counts as not answering
    [[channel]]                  # one per gauge: its position in the line, the tool axis, sign and scale
    index = 0
    axis = "y"
    sign = 1.0
    scale_mm = 0.001             # device unit -> mm
    [temperature]                # optional: a channel holding the temperature in degC
    index = 2
    [loader]                     # optional: a loader that can be commanded (non-interactive mode)
    command = "LOAD {axis} {phase} {mass_kg:.4f}\\r\\n"
    ack = "OK"

Plan (``rodlab.rigplan/1``)::

    format = "rodlab.rigplan/1"
    rod = "1#"
    axes = ["y", "z", "x"]
    masses_kg = [0.5, 1.0, 1.5, 2.0]
    repeats = 5
    hold_s = 8.0
    rate_Hz = 10.0
    [settle]                     # a hold starts once the readings stay within tolerance for window_s
    window_s = 1.0
    tolerance_mm = 0.003
    timeout_s = 30.0
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from rodlab.core.enums import Checksum, LineProtocol, LoadAxis
from rodlab.core.errors import did_you_mean
from rodlab.core.fileio import read_toml

from .errors import RigError
from .instrument_profile import parse_profile_v2
from .model import LoadSchedule
from rodlab.core.schema import require_schema

__all__ = ["Channel", "RigProfile", "RigPlan", "read_profile", "read_plan", "FORMAT_PROFILE", "FORMAT_PLAN"]

FORMAT_PROFILE = "rodlab.rigprofile/1"
FORMAT_PROFILE_V2 = "rodlab.rigprofile/2"
FORMAT_PLAN = "rodlab.rigplan/1"


def _load_toml(path) -> tuple[dict, str]:
    return read_toml(Path(path), RigError)


def _schema(data: dict, format_id: str, path, text: str) -> None:
    """The format's schema, after the reader's own rules: anything they let through is refused too."""
    require_schema(data, format_id, Path(path), text, RigError, kind="toml")


def _line(text: str, key: str) -> int | None:
    """The line of ``key`` (a dotted path such as ``instrument[2].channel[1].units``: 1-based indices of arrays of
    tables; ``settle.window_s``) in the TOML ``text``: inside the table it names, else its first occurrence
    anywhere (None when the key is not written)."""
    path = [(m.group(1), int(m.group(2)) if m.group(2) else None)
            for m in re.finditer(r"([^.\[\]]+)(?:\[(\d+)\])?", key)] or [(key, None)]
    *tables, leaf = path
    first, here, counts = None, [], {}
    for i, raw in enumerate(text.splitlines(), start=1):
        head = re.match(r"^\s*(\[\[?)\s*([\w.]+)\s*\]\]?", raw)
        if head:
            names = head.group(2).split(".")
            parent = tuple(here[:len(names) - 1])
            n = counts[(parent, names[-1])] = counts.get((parent, names[-1]), 0) + 1
            here = list(parent) + [(names[-1], n if head.group(1) == "[[" else None)]
            if leaf[1] is not None and here == path:      # the key names an array's table: its header line
                return i
            continue
        if re.match(rf"^\s*{re.escape(leaf[0])}\s*=", raw):
            first = first or i
            if len(here) == len(tables) and all(a == b[0] and (j is None or j == b[1])
                                                for (a, j), b in zip(tables, here)):
                return i
    return first


class _Reader:
    def __init__(self, path, text):
        self.path, self.text = path, text

    def err(self, msg, key):
        return RigError(msg, path=self.path, line=_line(self.text, key) if key else None, key=key)

    def keys(self, tbl, allowed, where):
        if not isinstance(tbl, dict):
            raise self.err("expected a table", where)
        for k in tbl:
            if k not in allowed:
                raise self.err(f"unknown key `{k}` in [{where}]; allowed: {sorted(allowed)}." + did_you_mean(k, allowed),
                               f"{where}.{k}" if where else k)

    def num(self, tbl, key, where, default=None, positive=True, integer=False):
        if key not in tbl:
            if default is None:
                raise self.err(f"missing required key `{key}`", f"{where}.{key}" if where else key)
            return default
        v = tbl[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or v != v or v in (float("inf"), float("-inf")):
            raise self.err(f"expected a finite number, got {v!r}", f"{where}.{key}" if where else key)
        if positive and v <= 0:
            raise self.err(f"expected a number > 0, got {v!r}", f"{where}.{key}" if where else key)
        if integer and int(v) != v:
            raise self.err(f"expected an integer, got {v!r}", f"{where}.{key}" if where else key)
        return int(v) if integer else float(v)

    def string(self, tbl, key, where, default=None, choices=None):
        if key not in tbl:
            if default is None:
                raise self.err(f"missing required key `{key}`", f"{where}.{key}" if where else key)
            return default
        v = tbl[key]
        if not isinstance(v, str):
            raise self.err(f"expected a string, got {v!r}", f"{where}.{key}" if where else key)
        if choices and v not in choices:
            raise self.err(f"expected one of {list(choices)}, got {v!r}." + did_you_mean(v, choices),
                           f"{where}.{key}" if where else key)
        return v


@dataclass(frozen=True)
class Channel:
    """A gauge: position ``index`` in the device line, tool ``axis`` (0..2), ``sign``, ``scale_mm`` per unit."""

    index: int
    axis: int
    sign: float = 1.0
    scale_mm: float = 1.0


@dataclass(frozen=True)
class RigProfile:
    """How the rig's instruments are wired (see the module docstring for the file format)."""

    port: str
    protocol: str
    channels: tuple
    baudrate: int = 9600
    bytesize: int = 8
    parity: str = "N"
    stopbits: float = 1
    timeout_s: float = 0.5
    request: str = "R\r\n"
    separator: str = ","
    checksum: str = "none"
    retries: int = 5
    temperature_index: int | None = None
    loader_command: str | None = None
    loader_ack: str = "OK"
    path: Path | None = field(default=None, compare=False)

    @property
    def n_values(self) -> int:
        idx = [c.index for c in self.channels] + ([self.temperature_index] if self.temperature_index is not None else [])
        return max(idx) + 1


def _got_format(data: dict) -> str:
    """What a file's ``format`` key says, for an error: its value, or that it has none."""
    return f"got {data['format']!r}" if data.get("format") else "the file has no format key"


def read_profile(path):
    """A rig profile: :class:`RigProfile` (``rodlab.rigprofile/1``, one port) or
    :class:`~.instrument_profile.InstrumentProfile` (``/2``, several instruments)."""
    data, text = _load_toml(path)
    r = _Reader(Path(path), text)
    if data.get("format") == FORMAT_PROFILE_V2:
        _schema(data, FORMAT_PROFILE_V2, path, text)
        return parse_profile_v2(data, r, path)
    r.keys(data, {"format", "device", "channel", "temperature", "loader"}, "")
    if data.get("format") != FORMAT_PROFILE:
        raise r.err(f"expected format = \"{FORMAT_PROFILE}\" or \"{FORMAT_PROFILE_V2}\", {_got_format(data)}", "format")
    dev = data.get("device")
    if dev is None:
        raise r.err("missing [device]", "device")
    r.keys(dev, {"port", "baudrate", "bytesize", "parity", "stopbits", "timeout_s", "protocol", "request",
                 "separator", "checksum", "retries"}, "device")
    chans = data.get("channel")
    if not isinstance(chans, list) or not chans:
        raise r.err("at least one [[channel]] is needed (index, axis, sign, scale_mm)", "channel")
    channels = []
    for ch in chans:
        r.keys(ch, {"index", "axis", "sign", "scale_mm"}, "channel")
        ax = r.string(ch, "axis", "channel", choices=("x", "y", "z"))
        sign = r.num(ch, "sign", "channel", 1.0, positive=False)
        if sign not in (1.0, -1.0):
            raise r.err(f"sign must be 1 or -1, got {sign}", "channel.sign")
        index = r.num(ch, "index", "channel", None, positive=False, integer=True)
        if index < 0:
            raise r.err(f"index is the value's place in the device line, from 0; got {index}", "channel.index")
        channels.append(Channel(index, "xyz".index(ax), sign, r.num(ch, "scale_mm", "channel", 1.0)))
    if len({c.axis for c in channels}) != len(channels):
        raise r.err("two channels measure the same tool axis", "channel.axis")
    temp = data.get("temperature")
    t_index = None
    if temp is not None:
        r.keys(temp, {"index"}, "temperature")
        t_index = r.num(temp, "index", "temperature", None, positive=False, integer=True)
        if t_index < 0:
            raise r.err(f"index is the value's place in the device line, from 0; got {t_index}", "temperature.index")
    loader = data.get("loader")
    cmd, ack = None, "OK"
    if loader is not None:
        r.keys(loader, {"command", "ack"}, "loader")
        cmd = r.string(loader, "command", "loader").encode().decode("unicode_escape")
        ack = r.string(loader, "ack", "loader", "OK")
    _schema(data, FORMAT_PROFILE, path, text)
    return RigProfile(
        port=r.string(dev, "port", "device"), protocol=r.string(dev, "protocol", "device", LineProtocol.QUERY.value,
                                                                   tuple(m.value for m in LineProtocol)),
        channels=tuple(channels), baudrate=r.num(dev, "baudrate", "device", 9600, integer=True),
        bytesize=r.num(dev, "bytesize", "device", 8, integer=True),
        parity=r.string(dev, "parity", "device", "N", ("N", "E", "O")),
        stopbits=r.num(dev, "stopbits", "device", 1.0), timeout_s=r.num(dev, "timeout_s", "device", 0.5),
        request=r.string(dev, "request", "device", "R\\r\\n").encode().decode("unicode_escape"),
        separator=r.string(dev, "separator", "device", ","),
        checksum=r.string(dev, "checksum", "device", Checksum.NONE.value, tuple(m.value for m in Checksum)),
        retries=r.num(dev, "retries", "device", 5, integer=True), temperature_index=t_index,
        loader_command=cmd, loader_ack=ack, path=Path(path))


@dataclass(frozen=True)
class RigPlan:
    """What to record: the load schedule, the settle rule [s, mm], the rod's name; ``measured_stated``: the load axes
    whose measured components the plan file lists (``[measured]``)."""

    rod: str
    schedule: LoadSchedule
    settle_window_s: float = 1.0
    settle_tolerance_mm: float = 0.003
    settle_timeout_s: float = 30.0
    path: Path | None = field(default=None, compare=False)
    measured_stated: frozenset = frozenset()

    def recorded(self, axis: str) -> tuple:
        """The components (0..2) an acquisition records under the load ``axis``: those the plan lists for it, else
        every gauge the rig has (a technician trial: the schedule's default x and z under a z load had dropped a
        wired y gauge's readings without a word)."""
        return tuple(self.schedule.measured[axis]) if axis in self.measured_stated else (0, 1, 2)


def read_plan(path) -> RigPlan:
    data, text = _load_toml(path)
    r = _Reader(Path(path), text)
    r.keys(data, {"format", "rod", "axes", "masses_kg", "repeats", "hold_s", "rate_Hz", "settle", "measured"}, "")
    if data.get("format") != FORMAT_PLAN:
        raise r.err(f"expected format = \"{FORMAT_PLAN}\", {_got_format(data)}", "format")
    rod = r.string(data, "rod", "")
    axes = data.get("axes", ["y", "z", "x"])
    if not isinstance(axes, list) or not axes:
        raise r.err("axes must be a non-empty list such as [\"y\", \"z\", \"x\"]", "axes")
    for a in axes:
        if a not in [x.value for x in LoadAxis]:
            raise r.err(f"unknown load axis {a!r}; expected one of {[x.value for x in LoadAxis]}", "axes")
    masses = data.get("masses_kg", [0.5, 1.0, 1.5, 2.0])
    if not isinstance(masses, list) or not masses or any(isinstance(m, bool) or not isinstance(m, (int, float))
                                                          or not (m > 0 and m < float("inf")) for m in masses):
        raise r.err("masses_kg must be a non-empty list of finite masses > 0 [kg]", "masses_kg")
    if any(b <= a for a, b in zip(masses, masses[1:])):
        raise r.err("masses_kg must increase strictly (the loading branch), e.g. [0.5, 1.0, 1.5, 2.0]", "masses_kg")
    settle = data.get("settle", {})
    r.keys(settle, {"window_s", "tolerance_mm", "timeout_s"}, "settle")
    measured = dict(LoadSchedule().measured)
    meas = data.get("measured", {})
    r.keys(meas, [a.value for a in LoadAxis], "measured")
    for k, v in meas.items():
        if not isinstance(v, list) or any(c not in ("x", "y", "z") for c in v):
            raise r.err("each entry lists measured components, e.g. y = [\"y\", \"z\"]", f"measured.{k}")
        measured[k] = tuple("xyz".index(c) for c in v)
    try:
        proto = LoadSchedule(axes=tuple(axes), masses=tuple(float(m) for m in masses),
                             repeats=r.num(data, "repeats", "", 5, integer=True), hold_s=r.num(data, "hold_s", "", 8.0),
                             rate_Hz=r.num(data, "rate_Hz", "", 10.0), measured=measured)
    except RigError as e:                       # a rule of the whole schedule (a hold shorter than one sample)
        if e.path is not None:
            raise
        raise r.err(e.detail, e.key or "") from e
    _schema(data, FORMAT_PLAN, path, text)
    if len(proto.masses) == 1 and int(proto.repeats) == 1:     # a technician trial: acquired, then not fittable
        raise r.err(f"one mass hung once gives each load axis two holds besides its zero reference "
                    f"({proto.masses[0]:g} kg and 0 kg unloading); the load-deflection fit needs three: add a mass or "
                    "a repeat", "repeats" if "repeats" in data else "masses_kg")
    return RigPlan(rod, proto, r.num(settle, "window_s", "settle", 1.0), r.num(settle, "tolerance_mm", "settle", 0.003),
                   r.num(settle, "timeout_s", "settle", 30.0), Path(path), frozenset(meas))
