"""Talking to the rig's gauge counter over pyserial: readings, loader commands, retries, reconnects.

Garbage (bad checksum, wrong value count, non-numbers, partial lines) is counted and logged, never fatal.
A device that stops answering is retried ``profile.retries`` times, then the port is reopened (a replugged
USB cable comes back under the same path) with a growing pause; only after that does :class:`DeviceError`
say what to check. pyserial is imported here, so the core install suffices on a rig PC.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from .config import RigProfile
from .errors import DeviceError
from .protocol import parse_line

__all__ = ["GaugeClient"]

log = logging.getLogger(__name__)


class GaugeClient:
    """Readings in mm in {T} from the gauges described by ``profile``."""

    def __init__(self, profile: RigProfile, reconnect_attempts: int = 8) -> None:
        self.profile = profile
        self.reconnect_attempts = reconnect_attempts
        self.garbage = 0
        self.timeouts = 0
        self.reconnects = 0
        self._ser = None
        self._open()

    # -- connection ----------------------------------------------------------------------------
    def _open(self) -> None:
        import serial
        p = self.profile
        try:
            self._ser = serial.serial_for_url(p.port, baudrate=p.baudrate, bytesize=p.bytesize, parity=p.parity,
                                              stopbits=p.stopbits, timeout=p.timeout_s, write_timeout=p.timeout_s)
        except (serial.SerialException, OSError, ValueError) as e:
            raise DeviceError(f"cannot open the gauge counter at {p.port!r}: {e}; check the cable, the port name in "
                              f"the profile and that no other program holds the port", path=p.path,
                              key="device.port") from e

    def _reconnect(self, why: str) -> None:
        log.warning("gauge counter: %s; reconnecting to %s", why, self.profile.port)
        self.close()
        delay = 0.05
        for attempt in range(self.reconnect_attempts):
            time.sleep(delay)
            try:
                self._open()
                self.reconnects += 1
                return
            except DeviceError:
                delay = min(2 * delay, 2.0)
        raise DeviceError(f"the gauge counter at {self.profile.port!r} is gone ({why}) and did not come back after "
                          f"{self.reconnect_attempts} attempts; check the cable and power, then re-run the same "
                          f"command: it resumes after the last complete hold", path=self.profile.path,
                          key="device.port") from None

    def close(self) -> None:
        if self._ser is not None:
            try:
                self._ser.close()
            except Exception:  # noqa: BLE001 - closing a dead port
                pass
            self._ser = None

    # -- I/O -------------------------------------------------------------------------------------
    def _readline(self) -> bytes:
        import serial
        try:
            return self._ser.readline()
        except (serial.SerialException, OSError) as e:
            self._reconnect(f"read failed ({e})")
            return b""

    def _write(self, data: bytes) -> None:
        import serial
        try:
            self._ser.write(data)
            self._ser.flush()
        except (serial.SerialException, OSError) as e:
            self._reconnect(f"write failed ({e})")

    def _decode(self, raw: bytes):
        p = self.profile
        vals = parse_line(raw, p.n_values, p.separator, p.checksum)
        if vals is None:
            if raw.strip():
                self.garbage += 1
                log.info("gauge counter: garbage line ignored (%d so far): %r", self.garbage, raw[:60])
            return None
        x = np.full(3, np.nan)
        for ch in p.channels:
            x[ch.axis] = ch.sign * ch.scale_mm * vals[ch.index]
        temp = vals[p.temperature_index] if p.temperature_index is not None else None
        return x, temp

    def read(self):
        """One reading: (displacement [mm] shape=(3,), NaN where no gauge; temperature [degC] or None)."""
        p = self.profile
        failures = 0
        while True:
            if p.protocol == "query":
                try:
                    self._ser.reset_input_buffer()
                except Exception:  # noqa: BLE001
                    self._reconnect("port lost")
                self._write(p.request.encode("ascii"))
            raw = self._readline()
            got = self._decode(raw) if raw else None
            if got is not None:
                return got
            if not raw:
                self.timeouts += 1
            failures += 1
            if failures >= p.retries:
                self._reconnect(f"no valid reading in {failures} attempts")
                failures = 0

    def read_sample(self):
        """One reading as a :class:`~.instruments.Sample` (no load cell on a one-port counter)."""
        from .instruments import Sample
        x, temp = self.read()
        return Sample(x, temp)

    def command_loader(self, axis: str, phase: str, mass_kg: float) -> None:
        """Command the loader (profile ``[loader]``) and wait for its acknowledgement."""
        p = self.profile
        if p.loader_command is None:
            raise DeviceError("the profile has no [loader]; run interactively (the operator hangs the weights)",
                              path=p.path, key="loader")
        cmd = p.loader_command.format(axis=axis, phase=phase, mass_kg=mass_kg).encode("ascii")
        for _ in range(p.retries):
            try:
                self._ser.reset_input_buffer()
            except Exception:  # noqa: BLE001
                self._reconnect("port lost")
            self._write(cmd)
            deadline = time.monotonic() + max(p.timeout_s, 0.2) * 4
            while time.monotonic() < deadline:
                raw = self._readline()
                if raw.strip().decode("ascii", "replace") == p.loader_ack:
                    return
                if raw.strip():
                    self.garbage += 1
        raise DeviceError(f"the loader did not acknowledge {cmd!r} after {p.retries} attempts", path=p.path,
                          key="loader.command")
