"""Acquisition: run a plan on the rig and append every sample to the contract CSV as it arrives.

- One process per recording: an exclusive lock on ``RECORDING.lock`` refuses a second one.
- Resumable: after each hold a comment line ``# hold K/N complete: step S`` is appended (the contract reader
  skips comment lines); a re-run of the same command continues with the hold after the last complete one.
  An interrupted hold keeps its samples and is recorded again under a new step number. The zero reading of
  each series is kept as ``# zero AXIS: x, y, z`` so a resumed series keeps its zero. Only the same plan,
  rate and device may continue a file (:mod:`.resume`); the lock file is removed when the run ends.
- Every load axis's series starts with a mass-0 hold; its settled mean is the zero that all readings of the
  series are referred to (the contract: relative to the unloaded reading at the start of the series).
- A hold starts once the live readings stay within ``settle_tolerance_mm`` for ``settle_window_s`` (or after
  ``settle_timeout_s``, with a warning); settling samples are recorded too (the fit skips the start of each
  hold). Then ``hold_s`` seconds are recorded at ``rate_Hz``.
"""
from __future__ import annotations

import contextlib
import logging
import math
import os
import time
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np
from filelock import FileLock, Timeout

from rodlab.core.units import G0

from .config import RigPlan, RigProfile
from .device import GaugeClient
from .instruments import RigClient, Sample
from .errors import RigError
from .fit_checks import scale_cause
from .recording import RecordingWriter
from .recording_header import LOAD_BY_CELL, LOAD_BY_MASS
from .resume import ResumePoint, identity_meta, resume_point

__all__ = ["AcquisitionStatus", "acquire", "RecordingLock"]

log = logging.getLogger(__name__)

#: a load cell's reading above its unloaded start against the hung weight: outside this ratio it is said at once,
#: a gross slip (a scale 10x off, another unit, the sign); friction and a hanger's tare stay inside it (a review: a
#: 0.3 kg tare on 0.5 kg reads 1.5x)
LOAD_RATIO = (0.3, 3.0)
#: ... for weights of at least this much [N] (a light first mass is mostly friction and tare)
LOAD_CHECK_MIN_N = 4.0

@dataclass
class AcquisitionStatus:
    """Progress: holds done / total, the hold being recorded, counters."""

    holds_done: int
    holds_total: int
    label: str
    samples: int
    garbage: int
    reconnects: int
    #: requests the instruments left unanswered and were repeated (each delays its sample by the port's timeout)
    timeouts: int = 0


class RecordingLock:
    """Exclusive lock on ``<recording>.lock`` (filelock: fcntl on POSIX, msvcrt on Windows; released on close or
    process death), the lock file removed when released."""

    def __init__(self, recording: Path) -> None:

        self.path = Path(str(recording) + ".lock")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._lock = FileLock(str(self.path))
        try:
            self._lock.acquire(timeout=0)
        except Timeout:
            self._lock = None
            raise RigError("another acquisition is writing this recording (it holds the lock); wait for it or "
                           "choose another output file", path=recording) from None

    def release(self) -> None:
        """Release the lock and remove its file (on POSIX removed first: no one can lock a file about to go;
        on Windows the open file cannot be removed, filelock removes it on release)."""
        if self._lock is not None:
            if os.name == "posix":
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(self.path)
            self._lock.release()
            self._lock = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


def acquire(profile: RigProfile, plan: RigPlan, out: str | Path, operator: Callable[[str], None] | None = None,
            progress: Callable[[AcquisitionStatus], None] | None = None, client: GaugeClient | None = None,
            use_loader: bool | None = None) -> Path:
    """Record ``plan`` into ``out``; resumes an interrupted recording of the same plan, rate and device.

    ``operator(prompt)`` is called before each hold when there is no commandable loader (it returns when the
    weight hangs); with ``use_loader`` (default: when the profile has a ``[loader]``) the loader is commanded.
    A file of another plan, rate or device is refused (:func:`.resume.resume_point`).
    """
    out = Path(out)
    use_loader = profile.loader_command is not None if use_loader is None else use_loader
    if not use_loader and operator is None:
        raise RigError("no loader in the profile and no operator prompt: run interactively or add [loader]",
                       path=profile.path, key="loader")
    if use_loader and profile.loader_command is None and client is None:
        raise RigError("--non-interactive commands the loader, but the profile has no [loader]; add one or run "
                       "interactively (the operator hangs the weights)", path=profile.path, key="loader")
    with RecordingLock(out):
        start = resume_point(out, profile, plan)
        if start.complete:
            log.info("%s: the plan is already complete (%d holds)", out, start.holds_total)
            return out
        own_client = client is None
        client = client or make_client(profile)
        with_force = bool(getattr(profile, "has_force", False))
        meta = {"rod": plan.rod, **identity_meta(profile, plan),
                "load_N": f"{LOAD_BY_CELL})" if with_force else LOAD_BY_MASS,
                "plan": str(plan.path or ""), "profile": str(profile.path or ""), "generator": "rodlab rig acquire"}
        with_temp = profile.has_temperature if hasattr(profile, "has_temperature") else \
            profile.temperature_index is not None
        writer = RecordingWriter(out, meta, with_temp=with_temp, fsync_every=20, with_force=with_force,
                                 decimals=6)                   # raw gauge resolution kept (nm)
        try:
            if start.holds_done:
                writer.comment(f"resumed after hold {start.holds_done}/{start.holds_total}")
            _Session(plan, client, writer, start, operator if not use_loader else None, progress).run()
        except BaseException:
            try:
                if writer.discard_if_empty():
                    log.info("%s: removed (no sample was recorded)", out)
            except OSError as e:                   # the original error is the one to see
                log.warning("%s: not removed (%s); it holds no sample", out, e)
            raise
        finally:
            writer.close()
            if own_client:
                client.close()
    return out


def make_client(profile):
    """The client of a profile: one port (``rodlab.rigprofile/1``) or several instruments (``/2``)."""
    return RigClient(profile) if hasattr(profile, "instruments") else GaugeClient(profile)


class _Session:
    """One run of the plan's remaining holds into an open recording."""

    def __init__(self, plan: RigPlan, client: GaugeClient, writer: RecordingWriter, start: ResumePoint,
                 operator, progress) -> None:
        self.plan, self.client, self.writer = plan, client, writer
        self.operator, self.progress = operator, progress
        self.start = start
        self.zeros = dict(start.zeros or {})
        self.step = start.last_step
        self.samples = 0
        self.dt = 1.0 / plan.schedule.rate_Hz
        self.t0 = time.monotonic() - (start.last_time_s + 1.0 if start.last_time_s >= 0 else 0.0)
        self.tick = time.monotonic()
        self.skew_s = 0.0
        self.forces: list[float] = []              # the load cell's readings of the hold being recorded [N]
        self.force_zero: dict[str, float] = {}     # per load axis, the load cell at its unloaded start [N]
        self.load_warned = False

    def run(self) -> None:
        holds = self.plan.schedule.holds()
        for k in range(self.start.holds_done, len(holds)):
            axis, rep, phase, mass = holds[k]
            self.step += 1
            label = f"hold {k + 1}/{len(holds)}: {mass:g} kg on {axis.value} ({phase}, repeat {rep})"
            self._set_load(axis, rep, phase, mass)
            self._record_hold(axis, rep, phase, mass, label)
            if self.skew_s > 0:
                self.writer.comment(f"instruments step {self.step}: answers within {self.skew_s * 1e3:.1f} ms")
                self.skew_s = 0.0
            self.writer.comment(f"hold {k + 1}/{len(holds)} complete: step {self.step}")
            self.writer.sync()
            if self.progress:
                self.progress(AcquisitionStatus(k + 1, len(holds), label, self.samples, self.client.garbage,
                                                self.client.reconnects, getattr(self.client, "timeouts", 0)))

    def _set_load(self, axis, rep, phase, mass) -> None:
        if self.operator is None:
            self.client.command_loader(axis.value, str(phase), mass)
        elif mass > 0:
            self.operator(f"Hang {mass:g} kg on the {axis.value} hanger ({phase}, repeat {rep}) then press Enter")
        else:
            self.operator(f"Remove all weights ({axis.value} series, {phase}) then press Enter")

    def _sample(self):
        """One reading at the plan's rate: (time [s], gauges [mm] shape=(3,), temperature [degC], force [N])."""
        self.tick += self.dt
        pause = self.tick - time.monotonic()
        if pause > 0:
            time.sleep(pause)
        else:
            self.tick = time.monotonic()
        if hasattr(self.client, "read_sample"):
            s = self.client.read_sample()
            self.skew_s = max(self.skew_s, s.skew_s)
        else:                                          # a client of one port (tests may pass their own)
            s = Sample(*self.client.read())
        return time.monotonic() - self.t0, s.x, s.temp, s.force

    def _emit(self, hold, t, x, temp, force=math.nan) -> None:
        axis, rep, phase, mass = hold
        measured = self.plan.recorded(axis.value)
        rel = x - self.zeros.get(axis.value, np.zeros(3))
        disp = tuple(float(rel[c]) if c in measured and math.isfinite(rel[c]) else math.nan for c in range(3))
        self.writer.write(t, self.step, rep, phase, axis, mass, disp, temp, force)
        self.samples += 1
        if math.isfinite(force):
            self.forces.append(force)

    def _record_hold(self, axis, rep, phase, mass, label) -> None:
        """Settle (samples recorded too; a new series' zero is their settled mean), then ``hold_s`` seconds."""
        hold = (axis, rep, phase, mass)
        new_series = (mass == 0.0 and phase.value == "load" and rep == 1) or axis.value not in self.zeros
        self.forces = []
        settled = self._settle(hold, label, buffer=new_series)
        if new_series:
            recent, buffered = settled
            with warnings.catch_warnings():              # a tool axis without a gauge stays NaN
                warnings.simplefilter("ignore", RuntimeWarning)
                self.zeros[axis.value] = np.nanmean(np.array(recent), axis=0)
            self.writer.comment(f"zero {axis.value}: " + ", ".join(f"{v:.6f}" for v in self.zeros[axis.value]))
            for item in buffered:
                self._emit(hold, *item)
        for _ in range(int(round(self.plan.schedule.hold_s * self.plan.schedule.rate_Hz))):
            self._emit(hold, *self._sample())
        self._check_load(hold, label, new_series)

    def _check_load(self, hold, label: str, new_series: bool) -> None:
        """Say at once (log and a comment line) when a load cell's reading above its unloaded start is not the hung
        mass's weight within :data:`LOAD_RATIO` (its scale, units, sign or Modbus word order), instead of at the
        fit after the whole plan (an instrument trial)."""
        axis, _, _, mass = hold
        if not self.forces:
            return
        mean = float(np.mean(self.forces))
        if new_series or axis.value not in self.force_zero:
            if mass == 0.0:
                self.force_zero[axis.value] = mean
            return
        weight, read = mass * G0, mean - self.force_zero[axis.value]
        if self.load_warned or weight < LOAD_CHECK_MIN_N or LOAD_RATIO[0] <= read / weight <= LOAD_RATIO[1]:
            return
        self.load_warned = True
        cause, fix = scale_cause(read / weight, axis.value)
        text = (f"{label}: the load cell reads {read:.4g} N above its unloaded start for {mass:g} kg ({weight:.4g} "
                f"N, a ratio of {read / weight:.4g}): {cause}. {fix} Every sample is kept (Ctrl-C and the same "
                f"command resumes)")
        log.warning("%s", text)
        self.writer.comment(f"load check: {text}")

    def _settle(self, hold, label, buffer: bool):
        """Read until the measured gauges stay within the tolerance for the window (or the timeout); returns
        (the last window's readings, the buffered samples) when ``buffer`` (a new series has no zero yet)."""
        plan = self.plan
        measured = list(plan.recorded(hold[0].value))
        window = max(int(round(plan.settle_window_s * plan.schedule.rate_Hz)), 2)
        recent, buffered = [], []
        t_start = time.monotonic()
        while True:
            t, x, temp, force = self._sample()
            recent.append(x)
            if buffer:
                buffered.append((t, x, temp, force))
            else:
                self._emit(hold, t, x, temp, force)
            if len(recent) >= window and np.nanmax(np.ptp(np.array(recent[-window:])[:, measured], axis=0)) <= \
                    plan.settle_tolerance_mm:
                break
            if time.monotonic() - t_start > plan.settle_timeout_s:
                log.warning("%s did not settle within %.0f s (tolerance %.3g mm); recording anyway",
                            label, plan.settle_timeout_s, plan.settle_tolerance_mm)
                break
        return recent[-window:], buffered
