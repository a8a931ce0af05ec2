"""Write a stiffness-rig recording straight from the physical model (no serial link): ``rodlab rig simulate``."""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .model import Hold, LoadSchedule, RigModel
from .recording import RecordingWriter
from .recording_header import LOAD_BY_CELL, LOAD_BY_MASS

__all__ = ["simulate_recording"]

def simulate_recording(model: RigModel, schedule: LoadSchedule, path: str | Path, rod: str = "rod",
                       extra_meta: dict | None = None) -> Path:
    """Run the load ``schedule`` on ``model`` and write every sample to ``path`` (contract ``rodlab.rig/1``)."""
    meta = {"rod": rod, "sample_rate_Hz": f"{schedule.rate_Hz:g}", "resolution_mm": f"{model.resolution_mm:g}",
            "load_N": LOAD_BY_MASS, "generator": "rodlab rig simulate"}
    if model.has_load_cell:
        meta["load_N"] = f"{LOAD_BY_CELL}, noise {model.load_cell_noise_N:g} N)"
    meta.update(extra_meta or {})
    model.with_plan(schedule.masses)
    p = Path(path)
    tmp = p.with_name(f".{p.name}.{os.getpid()}.part")     # written whole, then renamed: never a partial file
    try:
        _write_samples(model, schedule, tmp, meta)
        os.replace(tmp, p)
    finally:
        if tmp.exists():
            tmp.unlink()
    return p


def _write_samples(model: RigModel, schedule: LoadSchedule, p: Path, meta: dict) -> None:
    """Every sample of ``schedule`` on ``model`` into a new recording ``p``."""
    dt = 1.0 / schedule.rate_Hz
    n = int(round(schedule.hold_s * schedule.rate_Hz))
    t = 0.0
    current_axis = None
    offset = np.zeros(3)
    with RecordingWriter(p, meta, with_temp=True, fsync_every=10_000, with_force=model.has_load_cell) as w:
        for step, (axis, rep, phase, mass) in enumerate(schedule.holds(), start=1):
            hold = Hold(step, axis, rep, phase, mass, t)
            measured = schedule.measured.get(axis.value, (axis.index,))
            if axis is not current_axis:            # rod remounted; gauges zeroed on the unloaded reading
                current_axis = axis
                model.reset_series()
                offset = model.zero_reading(t, hold)
            for k in range(n):
                ts = t + k * dt
                x, temp = model.reading(ts, hold, measured)
                x = x - offset
                if model.resolution_mm > 0:
                    x = np.round(x / model.resolution_mm) * model.resolution_mm
                w.write(round(ts, 3), step, rep, phase, axis, mass, tuple(x), temp, model.load_cell(hold))
            t += n * dt + schedule.gap_s
