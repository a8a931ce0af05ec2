"""Simulated instruments on real pseudo-terminals, one per protocol of :mod:`.drivers`, all reading one
simulated rig (:class:`SimBench`): gauges, a load cell, a temperature sensor, a commandable loader.

Each instrument publishes its pty at a symlink (the profile's port); a disconnect closes the pty and opens a
new one behind the same path after a while, as an unplugged and replugged USB cable looks. Faults per answer:
garbage bytes, dropped answers, stalls, disconnects. Every valid answer is logged in ``sent`` and every fault
in ``events``, so a test can check what the recording holds against what was sent.
"""
from __future__ import annotations

import os
import random
import re
import select
import struct
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.core.enums import LoadAxis, Phase

from .drivers.base import unescape
from .drivers.digimatic import format_digimatic
from .instrument_profile import UNITS
from .model import Hold, RigModel
from .ptylink import PtyLink
from .protocol import encode_values, line_checksum
from .regex_template import template_of
from .simdevice import Faults

__all__ = ["SimBench", "PtyInstrument", "SimNumericLine", "SimAsciiRegex", "SimDigimatic", "SimModbusRTU",
           "Faults", "modbus_crc", "simulators_for", "template_of"]


class SimBench:
    """The simulated rig every simulated instrument reads: the rod on the rig (:class:`RigModel`, its load cell
    included) and the hold the loader set. ``state()`` gives one physical state for all instruments polled
    within ``coherence_s`` of each other."""

    def __init__(self, model: RigModel, coherence_s: float = 0.01, zero_mm=(0.1234, -0.0567, 0.007)) -> None:
        self.model = model
        self.coherence_s = coherence_s
        self.zero_mm = np.asarray(zero_mm, dtype=float)    # gauges do not read 0 unloaded
        self.hold = Hold(0, LoadAxis.Y, 1, Phase.LOAD, 0.0, 0.0)
        self._lock = threading.Lock()
        self._t0 = time.monotonic()
        self._last = (-1.0, None)

    def now(self) -> float:
        return time.monotonic() - self._t0

    def state(self) -> dict:
        """{x_mm, y_mm, z_mm, force_N, temp_C} of the rig now."""
        with self._lock:
            t = self.now()
            if self._last[1] is not None and t - self._last[0] < self.coherence_s:
                return self._last[1]
            x, temp = self.model.reading(t, self.hold, (0, 1, 2))
            force = self.model.load_cell(self.hold) if self.model.has_load_cell else 0.0
            x = x + self.zero_mm
            st = {"x_mm": x[0], "y_mm": x[1], "z_mm": x[2], "force_N": force, "temp_C": temp}
            self._last = (t, st)
            return st

    def value(self, channel) -> float:
        """What an instrument sends for ``channel`` (an :class:`~.instrument_profile.InstrumentChannel`): the
        rig's quantity in the channel's units, before its sign and scale (the inverse of ``channel.convert``)."""
        st = self.state()
        q = {"displacement": lambda: st["xyz"[channel.axis] + "_mm"], "force": lambda: st["force_N"],
             "temperature": lambda: st["temp_C"]}[channel.quantity]()
        return q / (channel.sign * channel.scale * UNITS[channel.quantity][channel.units])

    def command(self, text: str) -> bytes:
        """A loader line ``LOAD <axis> <phase> <mass_kg>`` -> ``OK`` (``ERR`` when malformed)."""
        parts = text.split()
        try:
            axis, phase, mass = LoadAxis(parts[1]), Phase(parts[2]), float(parts[3])
        except (IndexError, ValueError):
            return b"ERR\r\n"
        with self._lock:
            self.hold = Hold(self.hold.step + 1, axis, self.hold.repeat, phase, mass, self.now())
            self._last = (-1.0, None)
        return b"OK\r\n"


@dataclass
class PtyInstrument(PtyLink):
    """One simulated instrument behind a pty at ``link``. Subclasses implement :meth:`handle` (bytes in ->
    answers out) and, for a pushing device, :meth:`push`."""

    bench: SimBench
    link: Path
    faults: Faults = field(default_factory=Faults)
    seed: int = 0

    def __post_init__(self) -> None:
        self.link = Path(self.link)
        self.rand = random.Random(self.seed)
        self.sent: list = []
        self.events: list = []
        self._stop = threading.Event()
        self._master = self._slave = None
        self._thread = None
        self._buf = b""

    # -- behaviour ------------------------------------------------------------------------------
    def _write(self, data: bytes) -> None:
        try:
            os.write(self._master, data)
        except (OSError, TypeError):
            pass

    def _garbage(self) -> bytes:
        return bytes(self.rand.randrange(256) for _ in range(self.rand.randrange(3, 30))) + b"\r\n"

    def answer(self, make) -> None:
        """Send ``make()`` (bytes, logged in ``sent``) unless a fault hits this answer."""
        f, r = self.faults, self.rand.random
        if r() < f.disconnect:
            self.events.append((self.bench.now(), "disconnect"))
            self._close_pty()
            time.sleep(f.reconnect_after_s)
            self._open_pty()
            self._buf = b""
            return
        if r() < f.stall:
            self.events.append((self.bench.now(), "stall"))
            time.sleep(f.stall_s)
        if r() < f.drop:
            self.events.append((self.bench.now(), "drop"))
            return
        if r() < f.garbage:
            self.events.append((self.bench.now(), "garbage"))
            self._write(self._garbage())
            return
        data = make()
        self._write(data)
        self.sent.append((self.bench.now(), data))

    def handle(self, buf: bytes) -> bytes:
        """Act on the bytes received so far; return what is left unconsumed."""
        raise NotImplementedError

    def push(self) -> None:
        """A pushing device sends one line (called at ``rate_Hz`` when ``pushing``)."""

    pushing = False
    rate_Hz = 10.0

    def _run(self) -> None:
        next_push = time.monotonic()
        while not self._stop.is_set():
            fd = self._master
            if fd is None:
                time.sleep(0.01)
                continue
            timeout = max(0.0, min(0.02, next_push - time.monotonic())) if self.pushing else 0.02
            try:
                ready, _, _ = select.select([fd], [], [], timeout)
            except (OSError, ValueError):
                time.sleep(0.01)
                continue
            if ready:
                try:
                    self._buf += os.read(fd, 1024)
                except OSError:
                    self._buf = b""
                self._buf = self.handle(self._buf)
            if self.pushing and time.monotonic() >= next_push:
                next_push += 1.0 / self.rate_Hz
                self.push()


def _lines(buf: bytes, eol: bytes = b"\n"):
    """Complete lines of ``buf`` (CR or LF ended) and the rest."""
    out = []
    while True:
        cut = min([i for i in (buf.find(b"\r"), buf.find(b"\n")) if i >= 0], default=-1)
        if cut < 0:
            return out, buf
        line, buf = buf[:cut], buf[cut + 1:]
        if line.strip():
            out.append(line.decode("ascii", "replace").strip())


class _TextInstrument(PtyInstrument):
    """A text protocol: a ``LOAD ...`` line commands the loader, a request line is answered. With ``init`` set
    (an instrument in remote mode only on request) it answers and pushes nothing until that line came
    (acknowledged ``OK``)."""

    request = ""
    init = ""
    initialised = False

    def reply(self) -> bytes:
        raise NotImplementedError

    @property
    def ready(self) -> bool:
        return not self.init or self.initialised

    def handle(self, buf: bytes) -> bytes:
        lines, rest = _lines(buf)
        for text in lines:
            if text.upper().startswith("LOAD"):
                self._write(self.bench.command(text))
            elif self.init and text == self.init.strip():
                self.initialised = True
                self._write(b"OK\r\n")
            elif text == self.request.strip() and self.ready:
                self.answer(self.reply)
        return rest


@dataclass
class SimDigimatic(_TextInstrument):
    """A Mitutoyo Digimatic indicator on a serial interface: ``1`` + CR -> ``01A+00012.345`` + CR, the
    ball's displacement along ``axis`` [mm] (3 decimals, as the indicator shows) times ``sign``."""

    axis: str = "y"
    sign: float = 1.0
    channel: int = 1
    request: str = "1"
    source: object = None          # a callable giving the value (mm) instead of axis and sign

    def reply(self) -> bytes:
        v = self.source() if self.source else self.sign * self.bench.state()[f"{self.axis}_mm"]
        return format_digimatic(round(v, 3), self.channel)


@dataclass
class SimAsciiRegex(_TextInstrument):
    """A sensor controller: ``request`` -> ``template`` filled from the rig's state (``{x_mm}``, ``{y_um}``,
    ``{force_N}``, ``{temp_C}``, ... with format specs) + ``eol``; with an empty request it pushes lines."""

    template: str = "M0,{y_mm:+.5f},{z_mm:+.5f}"
    request: str = "M0"
    eol: str = "\r\n"

    def __post_init__(self) -> None:
        super().__post_init__()
        self.pushing = not self.request

    def _values(self) -> dict:
        st = dict(self.bench.state())
        st.update({f"{a}_um": st[f"{a}_mm"] * 1e3 for a in "xyz"})
        return st

    sources: dict = field(default_factory=dict)    # {template field: callable} beside the state's keys

    checksum: str = "none"
    pattern: str = ""              # the instrument's pattern: where its groups body and cs lie (a checksum)
    init: str = ""

    def reply(self) -> bytes:
        values = self._values()
        values.update({k: f() for k, f in self.sources.items()})
        text = self.template.format(**values, cs="00")
        if self.checksum != "none":
            m = re.search(self.pattern, text)
            cs = line_checksum(m.group("body").encode("ascii"), self.checksum)
            text = text[:m.start("cs")] + cs + text[m.end("cs"):]
        return (text + self.eol).encode("ascii")

    def push(self) -> None:
        if self.ready:
            self.answer(self.reply)


@dataclass
class SimNumericLine(_TextInstrument):
    """rodlab's original counter protocol on the shared bench: ``fields`` of the state (e.g. ``("x_um",
    "y_um", "z_um", "temp_C")``) as one line of numbers, query (``R``) or stream, optional XOR checksum."""

    fields: tuple = ("x_um", "y_um", "z_um", "temp_C")
    request: str = "R"
    stream: bool = False
    checksum: str = "none"

    def __post_init__(self) -> None:
        super().__post_init__()
        self.pushing = self.stream

    separator: str = ","

    def reply(self) -> bytes:
        st = dict(self.bench.state())
        st.update({f"{a}_um": st[f"{a}_mm"] * 1e3 for a in "xyz"})
        return encode_values([round(f() if callable(f) else st[f], 4) for f in self.fields], self.separator,
                             self.checksum)

    init: str = ""

    def push(self) -> None:
        if self.ready:
            self.answer(self.reply)


def modbus_crc(frame: bytes) -> bytes:
    """Modbus RTU CRC-16 (polynomial 0xA001, initial 0xFFFF), low byte first."""
    crc = 0xFFFF
    for b in frame:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return struct.pack("<H", crc)


def _words(value: float, kind: str, word_order: str) -> list[int]:
    """A value as 16-bit register words (``kind`` int16 / uint16 / int32 / uint32 / float32)."""
    if kind in ("int16", "uint16"):
        return [int(round(value)) & 0xFFFF]
    raw = struct.pack(">f", value) if kind == "float32" else struct.pack(">I", int(round(value)) & 0xFFFFFFFF)
    if word_order in ("BADC", "DCBA"):                          # bytes swapped within each word
        raw = bytes([raw[1], raw[0], raw[3], raw[2]])
    hi, lo = struct.unpack(">HH", raw)
    return [hi, lo] if word_order in ("big", "ABCD", "BADC") else [lo, hi]


@dataclass
class SimModbusRTU(PtyInstrument):
    """A load-cell amplifier speaking Modbus RTU (functions 3 and 4). ``registers``: {address: (state key,
    type, word_order, function, counts per unit)} -- e.g. ``{0: ("force_N", "float32", "big", 3, 1.0)}`` or
    ``{10: ("force_N", "int32", "little", 4, 1000.0)}`` (mN as an integer); other addresses answer exception 2."""

    slave: int = 1
    registers: dict = field(default_factory=lambda: {0: ("force_N", "float32", "big", 3, 1.0)})

    def _table(self, function: int) -> dict:
        st = self.bench.state()
        words = {}
        for addr, (key, kind, order, fc, per_unit) in self.registers.items():
            if fc == function:
                v = key() if callable(key) else st[key]
                for k, w in enumerate(_words(v * per_unit, kind, order)):
                    words[addr + k] = w
        return words

    def _respond(self, fc: int, start: int, count: int) -> bytes:
        table = self._table(fc)
        if count < 1 or any(a not in table for a in range(start, start + count)):
            body = bytes([self.slave, fc | 0x80, 2])
        else:
            data = b"".join(struct.pack(">H", table[a]) for a in range(start, start + count))
            body = bytes([self.slave, fc, len(data)]) + data
        return body + modbus_crc(body)

    def handle(self, buf: bytes) -> bytes:
        while len(buf) >= 8:
            frame, rest = buf[:8], buf[8:]
            if modbus_crc(frame[:6]) != frame[6:] or frame[0] != self.slave or frame[1] not in (3, 4):
                return b""                                  # out of step: drop what came (the master retries)
            fc, start, count = frame[1], *struct.unpack(">HH", frame[2:6])
            self.answer(lambda fc=fc, start=start, count=count: self._respond(fc, start, count))
            buf = rest
        return buf


def _source(bench: SimBench, channel):
    return lambda: bench.value(channel)


def simulators_for(profile, bench: SimBench, links: dict, faults: Faults | None = None) -> list:
    """One simulator per instrument of a ``rodlab.rigprofile/2`` profile on ``bench``, published at
    ``links[instrument name]``, answering with what its channels expect (units, sign, scale inverted)."""
    sims = []
    for k, ins in enumerate(profile.instruments):
        kw = {"bench": bench, "link": links[ins.name], "faults": faults or Faults(), "seed": k}
        c = ins.config
        by_value = {ch.value: _source(bench, ch) for ch in ins.channels}
        if ins.protocol == "digimatic":
            sims.append(SimDigimatic(**kw, request=unescape(c["request"]).strip(),
                                     source=by_value.get("value", lambda: 0.0)))
        elif ins.protocol == "numeric_line":
            fields = tuple(by_value.get(str(i), lambda: 0.0) for i in range(int(c["n_values"])))
            sims.append(SimNumericLine(**kw, fields=fields, request=unescape(c["request"]).strip(),
                                       stream=c["mode"] == "stream", checksum=c["checksum"], separator=c["separator"],
                                       init=unescape(c.get("init", "")).strip()))
        elif ins.protocol == "ascii_regex":
            template = template_of(c["pattern"], key=f"instruments.{ins.name}.pattern")
            sims.append(SimAsciiRegex(**kw, template=template, request=unescape(c["request"]).strip(),
                                      eol=unescape(c.get("eol", "\\n")), sources=by_value, pattern=c["pattern"],
                                      checksum=c.get("checksum", "none"), init=unescape(c.get("init", "")).strip()))
        elif ins.protocol == "modbus_rtu":
            regs = {}
            for r in ins.driver().registers:
                src = by_value.get(r["name"], lambda: 0.0)
                regs[r["address"]] = (src, r["type"], r["word_order"], r["function"], 1.0 / r["scale"])
            sims.append(SimModbusRTU(**kw, slave=int(c["slave"]), registers=regs))
        else:  # pragma: no cover - every registered driver has a branch (test_every_driver_has_a_simulator)
            raise KeyError(f"no simulator for protocol {ins.protocol!r}")
    return sims
