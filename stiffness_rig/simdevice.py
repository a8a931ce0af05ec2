"""A simulated stiffness rig on a real pseudo-terminal (``os.openpty``), for tests and demos.

It speaks the profile's protocol (``query``: answers each request line with one reading; ``stream``: pushes
``rate_Hz`` lines), driven by :class:`~stiffness_rig.model.RigModel`, and acts as a commandable loader
(``LOAD <axis> <phase> <mass_kg>`` -> ``OK``). The port is a symlink to the current pty so that a
disconnect (the pty closed) and reconnect (a new pty behind the same path) look like an unplugged and
replugged USB cable. Faults are injected at random: garbage bytes, dropped answers, partial lines, stalls,
disconnects and device resets. Every valid reading it sends is logged in :attr:`sent` so a test can check
that the recording holds them all.
"""
from __future__ import annotations

import os
import random
import select
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path


from rodlab.core.enums import LoadAxis, Phase

from .model import Hold, RigModel
from .ptylink import PtyLink
from .protocol import encode_values

__all__ = ["Faults", "SimulatedRig"]


@dataclass
class Faults:
    """Probabilities per answered line, and durations [s]."""

    garbage: float = 0.0
    drop: float = 0.0
    partial: float = 0.0
    stall: float = 0.0
    stall_s: float = 0.3
    disconnect: float = 0.0
    reconnect_after_s: float = 0.3
    reset: float = 0.0


@dataclass
class SimulatedRig(PtyLink):
    """The rig behind a pty. ``channels``: tool axis (0..2) of each value in a line, device units of
    ``scale_mm`` mm; ``temperature``: append the room temperature as the last value."""

    thread_name = "simulated-rig"

    model: RigModel
    link: Path
    protocol: str = "query"
    channels: tuple = (0, 1, 2)
    scale_mm: float = 0.001
    temperature: bool = True
    separator: str = ","
    checksum: str = "none"
    request: bytes = b"R\r\n"
    rate_Hz: float = 10.0
    faults: Faults = field(default_factory=Faults)
    seed: int = 0
    zero_offset_units: tuple = (123.4, -56.7, 7.0)   # gauges do not read 0 unloaded

    def __post_init__(self) -> None:
        self.link = Path(self.link)
        self.rand = random.Random(self.seed)
        self.hold = Hold(0, LoadAxis.Y, 1, Phase.LOAD, 0.0, 0.0)
        self.sent: list[tuple[float, tuple]] = []
        self.events: list[tuple[float, str]] = []
        self._stop = threading.Event()
        self._lock = threading.Lock()
        self._master = None
        self._slave = None
        self._thread = None
        self._t0 = time.monotonic()

    # -- behaviour -----------------------------------------------------------------------------------
    def now(self) -> float:
        return time.monotonic() - self._t0

    def _line(self) -> tuple[bytes, tuple]:
        t = self.now()
        with self._lock:
            hold = self.hold
        x, temp = self.model.reading(t, hold, (0, 1, 2))
        vals = [x[a] / self.scale_mm + self.zero_offset_units[a] for a in self.channels]
        if self.temperature:
            vals.append(temp)
        vals = [round(v, 4) for v in vals]
        return encode_values(vals, self.separator, self.checksum), tuple(vals)

    def _write(self, data: bytes) -> None:
        try:
            os.write(self._master, data)
        except OSError:
            pass

    def _answer(self) -> None:
        f = self.faults
        r = self.rand.random
        if r() < f.disconnect:
            self.events.append((self.now(), "disconnect"))
            self._close_pty()
            time.sleep(f.reconnect_after_s)
            self._open_pty()
            return
        if r() < f.stall:
            self.events.append((self.now(), "stall"))
            time.sleep(f.stall_s)
        if r() < f.drop:
            self.events.append((self.now(), "drop"))
            return
        if r() < f.garbage:
            self.events.append((self.now(), "garbage"))
            self._write(bytes(self.rand.randrange(256) for _ in range(self.rand.randrange(3, 30))) + b"\r\n")
            return
        if r() < f.reset:
            self.events.append((self.now(), "reset"))
            self._write(b"\r\nGAUGE COUNTER V2.1 READY\r\n")
            return
        line, vals = self._line()
        if r() < f.partial:
            self.events.append((self.now(), "partial"))
            self._write(line[: max(1, len(line) // 2)])
            return
        self._write(line)
        self.sent.append((self.now(), vals))

    def _command(self, text: str) -> None:
        parts = text.split()
        try:
            axis, phase, mass = LoadAxis(parts[1]), Phase(parts[2]), float(parts[3])
        except (IndexError, ValueError):
            self._write(b"ERR\r\n")
            return
        with self._lock:
            self.hold = Hold(self.hold.step + 1, axis, self.hold.repeat, phase, mass, self.now())
        self._write(b"OK\r\n")

    def _run(self) -> None:
        buf = b""
        next_push = time.monotonic()
        while not self._stop.is_set():
            fd = self._master
            if fd is None:
                time.sleep(0.01)
                continue
            timeout = 0.02
            if self.protocol == "stream":
                timeout = max(0.0, min(timeout, next_push - time.monotonic()))
            try:
                ready, _, _ = select.select([fd], [], [], timeout)
            except (OSError, ValueError):
                time.sleep(0.01)
                continue
            if ready:
                try:
                    chunk = os.read(fd, 1024)
                except OSError:
                    chunk = b""
                buf += chunk
                while b"\n" in buf:
                    line, buf = buf.split(b"\n", 1)
                    text = line.decode("ascii", "replace").strip()
                    if text.upper().startswith("LOAD"):
                        self._command(text)
                    elif self.protocol == "query" and (line + b"\n").endswith(self.request.rstrip(b"\r\n") + b"\n") \
                            or (self.protocol == "query" and text == self.request.decode().strip()):
                        self._answer()
            if self.protocol == "stream" and time.monotonic() >= next_push:
                next_push += 1.0 / self.rate_Hz
                self._answer()
