"""Several instruments read together: one client per instrument (its port, driver, retries, reconnects) and
the rig client that polls them all for one sample, in parallel, each answer with its own timestamp.

Garbage is counted and logged, never fatal. An instrument that does not answer is retried ``retries`` times,
then its port is reopened (a replugged USB cable comes back under the same path) with a growing pause; only
after that does :class:`~.errors.DeviceError` name the instrument, its port and what to check. The other
instruments wait for it (a sample is only written whole), so a slow or silent instrument delays the sample
and never shifts one instrument's readings against another's.
"""
from __future__ import annotations

import logging
import math
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field

import numpy as np
import serial

try:
    import termios
except ImportError:  # pragma: no cover - Windows
    termios = None

from .drivers import Garbage, Link, NoAnswer
from .errors import DeviceError
from .instrument_profile import Instrument, InstrumentProfile

__all__ = ["Sample", "InstrumentClient", "RigClient"]

log = logging.getLogger(__name__)


def _port_errors() -> tuple:
    """What a lost port raises: pyserial's error, OSError, and on POSIX termios.error (a flush on a pty whose
    other end closed), which is neither."""
    errors = (serial.SerialException, OSError)
    if termios is not None:
        errors += (termios.error,)
    return errors


@dataclass
class Sample:
    """One sample of the rig: displacement [mm] shape=(3,) in {T} (NaN where no gauge), temperature [degC] or
    None, the load cell's force along the load axis [N] (NaN without one), and each instrument's answer time
    {name: time.monotonic() [s]}."""

    x: np.ndarray
    temp: float | None = None
    force: float = math.nan
    times: dict = field(default_factory=dict)

    @property
    def skew_s(self) -> float:
        """Spread of the instruments' answer times [s] (0 for one instrument)."""
        t = list(self.times.values())
        return max(t) - min(t) if len(t) > 1 else 0.0


class InstrumentClient:
    """One instrument: its port opened with pyserial, its protocol's driver, retries and reconnects."""

    def __init__(self, instrument: Instrument, profile_path=None, reconnect_attempts: int = 8) -> None:
        self.instrument = instrument
        self.profile_path = profile_path
        self.reconnect_attempts = reconnect_attempts
        self.driver = instrument.driver()
        self.garbage = 0
        self.timeouts = 0
        self.last_garbage = ""
        self.reconnects = 0
        self.link: Link | None = None
        self._open()

    def _where(self) -> str:
        return f"instrument {self.instrument.name!r} ({self.instrument.protocol}) at {self.instrument.port!r}"

    def _open(self) -> None:
        i = self.instrument
        try:
            ser = serial.serial_for_url(i.port, baudrate=i.baudrate, bytesize=i.bytesize, parity=i.parity,
                                        stopbits=i.stopbits, timeout=i.timeout_s, write_timeout=i.timeout_s)
        except (serial.SerialException, OSError, ValueError) as e:
            raise DeviceError(f"cannot open {self._where()}: {e}; check the cable, the port name in the profile and "
                              f"that no other program holds the port", path=self.profile_path,
                              key="instrument.port") from e
        except Exception as e:  # termios.error: the port refused its line settings (not an OSError)
            if termios is None or not isinstance(e, termios.error):
                raise
            raise DeviceError(f"cannot open {self._where()}: the port refused its settings (baudrate {i.baudrate}, "
                              f"bytesize {i.bytesize}, parity {i.parity}, stopbits {i.stopbits:g}: {e}); check them "
                              f"against the instrument's manual in the profile; a pseudo-terminal (a simulator) has "
                              f"no parity bits: use parity = \"N\" there", path=self.profile_path,
                              key="instrument.parity") from e
        self.link = Link(ser)
        self.driver.after_reopen()
        try:
            self.driver.startup(self.link)
        except _port_errors() as e:
            self.close()
            raise DeviceError(f"cannot initialise {self._where()}: sending its init line failed ({e}); check the "
                              f"cable and the profile's `init`", path=self.profile_path, key="instrument.init") from e

    def _reconnect(self, why: str) -> None:
        log.warning("%s: %s; reconnecting", self._where(), why)
        self.close()
        delay = 0.05
        for _ in range(self.reconnect_attempts):
            time.sleep(delay)
            try:
                self._open()
                self.reconnects += 1
                return
            except DeviceError:
                delay = min(2 * delay, 2.0)
        raise DeviceError(f"{self._where()} is gone ({why}) and did not come back after {self.reconnect_attempts} "
                          f"attempts; check its cable and power, then re-run the same command: it resumes after the "
                          f"last complete hold", path=self.profile_path, key="instrument.port") from None

    def close(self) -> None:
        if self.link is not None:
            try:
                self.link.serial.close()
            except Exception:  # noqa: BLE001 - closing a dead port
                pass
            self.link = None

    def _poll_once(self):
        """The driver's values, or None after garbage / no answer (counted)."""
        try:
            return self.driver.poll(self.link)
        except Garbage as g:
            self.garbage += 1
            self.last_garbage = str(g)
            log.info("%s: garbage ignored (%d so far): %s", self._where(), self.garbage, g)
        except NoAnswer:
            self.timeouts += 1
            log.info("%s: no answer within the port's timeout (%d so far): request repeated", self._where(),
                     self.timeouts)
        except (*_port_errors(), AttributeError, TypeError) as e:
            self._reconnect(f"port lost ({type(e).__name__}: {e})")
        return None

    def read(self) -> tuple[dict, float]:
        """One reading: ({value name: number}, answer time ``time.monotonic()`` [s])."""
        failures = cycles = 0
        garbage0, timeouts0 = self.garbage, self.timeouts       # the counts of this reading, for its error
        self.last_garbage = ""                                  # an old answer is not this silence's cause
        while True:
            got = self._poll_once()
            if got is not None:
                return got, time.monotonic()
            failures += 1
            if failures >= self.instrument.retries:
                cycles += 1
                if cycles > self.reconnect_attempts:
                    last = (f"; the last: {self.last_garbage}" if self.last_garbage else
                            "; no answer at all (the request, the Modbus slave address or the baud rate?)")
                    raise DeviceError(f"{self._where()} answers nothing usable ({self.garbage - garbage0} garbage "
                                      f"answers, {self.timeouts - timeouts0} timeouts in a row) although its port "
                                      f"opens{last}; check its protocol "
                                      f"settings, baud rate and cable, then re-run the same command (a recording "
                                      f"already started resumes after its last complete hold)",
                                      path=self.profile_path, key="instrument")
                self._reconnect(f"no valid reading in {failures} attempts")
                failures = 0

    def command(self, text: str, ack: str, timeout_s: float) -> None:
        """Send one command line and wait for the acknowledgement line (the loader)."""
        for _ in range(self.instrument.retries):
            try:
                self.link.clear_input()
                self.link.write(text.encode("ascii"))
            except (*_port_errors(), AttributeError) as e:
                self._reconnect(f"write failed ({e})")
                continue
            deadline = time.monotonic() + timeout_s
            while time.monotonic() < deadline:
                try:
                    raw = self.link.readline()
                except NoAnswer:
                    continue
                except _port_errors() as e:
                    self._reconnect(f"read failed ({e})")
                    break
                if raw.strip().decode("ascii", "replace") == ack:
                    return
                if raw.strip():
                    self.garbage += 1
        raise DeviceError(f"the loader on {self._where()} did not acknowledge {text!r} after "
                          f"{self.instrument.retries} attempts", path=self.profile_path, key="loader.command")


class RigClient:
    """Every instrument of a ``rodlab.rigprofile/2`` profile, polled together for each sample."""

    def __init__(self, profile: InstrumentProfile, reconnect_attempts: int = 8) -> None:
        self.profile = profile
        self.clients: list[InstrumentClient] = []
        try:
            for ins in profile.instruments:
                self.clients.append(InstrumentClient(ins, profile.path, reconnect_attempts))
        except DeviceError:
            self.close()
            raise
        self._pool = ThreadPoolExecutor(max_workers=len(self.clients), thread_name_prefix="rig-instrument")

    @property
    def garbage(self) -> int:
        return sum(c.garbage for c in self.clients)

    @property
    def timeouts(self) -> int:
        return sum(c.timeouts for c in self.clients)

    @property
    def reconnects(self) -> int:
        return sum(c.reconnects for c in self.clients)

    def read_sample(self) -> Sample:
        """Poll every instrument at once; the sample when all have answered."""
        futures = [self._pool.submit(c.read) for c in self.clients]
        answers = [f.result() for f in futures]                      # a DeviceError of any one is raised here
        s = Sample(np.full(3, np.nan))
        for client, (values, t) in zip(self.clients, answers):
            s.times[client.instrument.name] = t
            for ch in client.instrument.channels:
                v = ch.convert(values[ch.value])
                if ch.quantity == "displacement":
                    s.x[ch.axis] = v
                elif ch.quantity == "force":
                    s.force = v
                else:
                    s.temp = v
        return s

    def read(self):
        """(displacement [mm] shape=(3,), temperature [degC] or None), as the one-port client gives."""
        s = self.read_sample()
        return s.x, s.temp

    def command_loader(self, axis: str, phase: str, mass_kg: float) -> None:
        p = self.profile
        if p.loader_command is None:
            raise DeviceError("the profile has no [loader]; run interactively (the operator hangs the weights)",
                              path=p.path, key="loader")
        client = next(c for c in self.clients if c.instrument.name == p.loader_instrument)
        client.command(p.loader_command.format(axis=axis, phase=phase, mass_kg=mass_kg), p.loader_ack,
                       max(client.instrument.timeout_s, 0.2) * 4)

    def close(self) -> None:
        for c in self.clients:
            c.close()
        pool = getattr(self, "_pool", None)
        if pool is not None:
            pool.shutdown(wait=False)
