"""Acquisition: run a plan on the rig and append every sample to the contract CSV as it arrives.

- One process per recording: an exclusive lock on ``RECORDING.lock`` refuses a second one.
- Resumable: after each hold a comment line ``# hold K/N complete: step S`` is appended (the contract reader
  skips comment lines); a re-run of the same command continues with the hold after the last complete one.
  An interrupted hold keeps its samples and is recorded again under a new step number. The zero reading of
  each series is kept as ``# zero AXIS: x, y, z`` so a resumed series keeps its zero.
- Every load axis's series starts with a mass-0 hold; its settled mean is the zero that all readings of the
  series are referred to (the contract: relative to the unloaded reading at the start of the series).
- A hold starts once the live readings stay within ``settle_tolerance_mm`` for ``settle_window_s`` (or after
  ``settle_timeout_s``, with a warning); settling samples are recorded too (the fit skips the start of each
  hold). Then ``hold_s`` seconds are recorded at ``rate_Hz``.
"""
from __future__ import annotations

import fcntl
import logging
import math
import os
import re
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from .config import RigPlan, RigProfile
from .device import GaugeClient
from .errors import RigError
from .recording import RecordingWriter, read_recording

__all__ = ["AcquisitionStatus", "acquire", "RecordingLock"]

log = logging.getLogger(__name__)

_DONE = re.compile(r"^# hold (\d+)/(\d+) complete: step (\d+)")
_ZERO = re.compile(r"^# zero (\S+): (.+)$")


@dataclass
class AcquisitionStatus:
    """Progress: holds done / total, the hold being recorded, counters."""

    holds_done: int
    holds_total: int
    label: str
    samples: int
    garbage: int
    reconnects: int


class RecordingLock:
    """Exclusive advisory lock on ``<recording>.lock`` (released on close or process death)."""

    def __init__(self, recording: Path) -> None:
        self.path = Path(str(recording) + ".lock")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(self._fd)
            raise RigError("another acquisition is writing this recording (it holds the lock); wait for it or "
                           "choose another output file", path=recording) from None
        os.ftruncate(self._fd, 0)
        os.write(self._fd, f"{os.getpid()}\n".encode())

    def release(self) -> None:
        if self._fd is not None:
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.release()


def _resume_state(path: Path):
    """(holds completed, last step, last time, zeros per axis) of an existing recording."""
    done, last_step, last_time, zeros = 0, 0, -1.0, {}
    if not path.exists() or path.stat().st_size == 0:
        return done, last_step, last_time, zeros
    text = path.read_text(encoding="utf-8", errors="replace")
    for line in text.splitlines():
        m = _DONE.match(line)
        if m:
            done = int(m.group(1))
        z = _ZERO.match(line)
        if z:
            zeros[z.group(1)] = np.array([float(v) for v in z.group(2).split(",")])
    if any(not ln.startswith("#") and ln.strip() and ln[0].isdigit() for ln in text.splitlines()):
        rec = read_recording(path)
        last_step, last_time = int(rec.step.max()), float(rec.time_s.max())
    return done, last_step, last_time, zeros


def acquire(profile: RigProfile, plan: RigPlan, out: str | Path, operator: Callable[[str], None] | None = None,
            progress: Callable[[AcquisitionStatus], None] | None = None, client: GaugeClient | None = None,
            use_loader: bool | None = None) -> Path:
    """Record ``plan`` into ``out``; resumes an interrupted recording of the same plan.

    ``operator(prompt)`` is called before each hold when there is no commandable loader (it returns when the
    weight hangs); with ``use_loader`` (default: when the profile has a ``[loader]``) the loader is commanded.
    """
    out = Path(out)
    holds = plan.protocol.holds()
    n_total = len(holds)
    use_loader = profile.loader_command is not None if use_loader is None else use_loader
    if not use_loader and operator is None:
        raise RigError("no loader in the profile and no operator prompt: run interactively or add [loader]",
                       path=profile.path, key="loader")
    with RecordingLock(out):
        done, step, last_time, zeros = _resume_state(out)
        if done >= n_total:
            log.info("%s: the plan is already complete (%d holds)", out, n_total)
            return out
        own_client = client is None
        client = client or GaugeClient(profile)
        meta = {"rod": plan.rod, "sample_rate_Hz": f"{plan.protocol.rate_Hz:g}", "load_N": "mass_kg * 9.80665",
                "plan": str(plan.path or ""), "profile": str(profile.path or ""), "generator": "rodlab rig acquire"}
        writer = RecordingWriter(out, meta, with_temp=profile.temperature_index is not None, fsync_every=20,
                                 decimals=6)                   # raw gauge resolution kept (nm)
        if done:
            writer._fh.write(f"# resumed after hold {done}/{n_total}\n")
        t0 = time.monotonic() - (last_time + 1.0 if last_time >= 0 else 0.0)
        dt = 1.0 / plan.protocol.rate_Hz
        n_hold = int(round(plan.protocol.hold_s * plan.protocol.rate_Hz))
        samples = 0
        try:
            for k in range(done, n_total):
                axis, rep, phase, mass = holds[k]
                step += 1
                label = f"hold {k + 1}/{n_total}: {mass:g} kg on {axis.value} ({phase}, repeat {rep})"
                if use_loader:
                    client.command_loader(axis.value, str(phase), mass)
                else:
                    operator(f"{'Hang' if mass > 0 else 'Remove all weights:'} {mass:g} kg on the {axis.value} "
                             f"hanger ({phase}, repeat {rep}) then press Enter" if mass > 0 else
                             f"Remove all weights ({axis.value} series, {phase}) then press Enter")
                measured = plan.protocol.measured.get(axis.value, (0, 1, 2))
                new_series = (mass == 0.0 and phase.value == "load" and rep == 1) or axis.value not in zeros
                buffered = []
                window = max(int(round(plan.settle_window_s * plan.protocol.rate_Hz)), 2)
                t_start = time.monotonic()
                tick = time.monotonic()

                def sample():
                    nonlocal tick
                    tick += dt
                    pause = tick - time.monotonic()
                    if pause > 0:
                        time.sleep(pause)
                    else:
                        tick = time.monotonic()
                    x, temp = client.read()
                    return time.monotonic() - t0, x, temp

                def emit(t, x, temp):
                    nonlocal samples
                    rel = x - zeros.get(axis.value, np.zeros(3))
                    disp = tuple(float(rel[c]) if c in measured and math.isfinite(rel[c]) else math.nan
                                 for c in range(3))
                    writer.write(t, step, rep, phase, axis, mass, disp, temp)
                    samples += 1

                # settle
                recent = []
                while True:
                    t, x, temp = sample()
                    recent.append(x)
                    if new_series:
                        buffered.append((t, x, temp))
                    else:
                        emit(t, x, temp)
                    if len(recent) >= window:
                        w = np.array(recent[-window:])[:, list(measured)]
                        if np.nanmax(np.ptp(w, axis=0)) <= plan.settle_tolerance_mm:
                            break
                    if time.monotonic() - t_start > plan.settle_timeout_s:
                        log.warning("%s did not settle within %.0f s (tolerance %.3g mm); recording anyway",
                                    label, plan.settle_timeout_s, plan.settle_tolerance_mm)
                        break
                if new_series:
                    zeros[axis.value] = np.nanmean(np.array(recent[-window:]), axis=0)
                    writer._fh.write(f"# zero {axis.value}: " + ", ".join(f"{v:.6f}" for v in zeros[axis.value]) + "\n")
                    for item in buffered:
                        emit(*item)
                for _ in range(n_hold):
                    emit(*sample())
                writer._fh.write(f"# hold {k + 1}/{n_total} complete: step {step}\n")
                writer._sync()
                if progress:
                    progress(AcquisitionStatus(k + 1, n_total, label, samples, client.garbage, client.reconnects))
        finally:
            writer.close()
            if own_client:
                client.close()
    return out
