"""Acquisition soak: random device faults and the acquiring process killed (SIGKILL) and restarted; the
recording completes the plan, every recorded reading is one the device sent, none twice, no torn lines."""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import numpy as np

from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.model import RigModel
from rodlab.stiffness_rig.simdevice import Faults, SimulatedRig

C = np.array([[0.0063, 0.0, -0.0151], [0.0, 0.2198, 0.0], [-0.0151, 0.0, 0.0666]])

SCRIPT = r"""
import sys
from rodlab.stiffness_rig.acquire import acquire
from rodlab.stiffness_rig.config import Channel, RigPlan, RigProfile
from rodlab.stiffness_rig.model import LoadSchedule
port, out = sys.argv[1], sys.argv[2]
prof = RigProfile(port=port, protocol="query", retries=3, timeout_s=0.15, temperature_index=3,
                  channels=tuple(Channel(i, i, 1.0, 0.001) for i in range(3)),
                  loader_command="LOAD {axis} {phase} {mass_kg:.4f}\r\n")
plan = RigPlan("1#", LoadSchedule(axes=("y", "z"), masses=(1.0, 2.0), repeats=2, hold_s=0.5, rate_Hz=20.0),
               settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=2.0)
acquire(prof, plan, out, use_loader=True)
"""


def _zero_of_each_row(text: str, rec) -> list:
    """The ``# zero AXIS`` line in effect [mm] for each data row of a recording, in file order."""
    zeros, out = {}, []
    for line in text.splitlines():
        if line.startswith("# zero"):
            ax, vals = line[7:].split(":")
            zeros[ax.strip()] = np.array([float(v) for v in vals.split(",")])
        elif line[:1].isdigit():
            out.append(zeros[rec.load_axis[len(out)].value])
    assert len(out) == rec.n
    return out


def test_soak_with_kills(tmp_path):
    out = tmp_path / "soak.rig.csv"
    faults = Faults(garbage=0.05, drop=0.03, partial=0.03, stall=0.02, stall_s=0.2, disconnect=0.01,
                    reconnect_after_s=0.2, reset=0.01)
    rng = np.random.default_rng(1)
    kills, runs = 0, 0
    with SimulatedRig(RigModel(C, seed=3), tmp_path / "tty", faults=faults, seed=5) as dev:
        env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
        while runs < 12:
            runs += 1
            proc = subprocess.Popen([sys.executable, "-c", SCRIPT, dev.port, str(out)], env=env,
                                    stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            if kills < 3:
                time.sleep(float(rng.uniform(2.0, 5.0)))
                if proc.poll() is None:
                    proc.send_signal(signal.SIGKILL)
                    proc.wait()
                    kills += 1
                    continue
            try:
                proc.wait(timeout=120)
            except subprocess.TimeoutExpired:
                proc.kill()
                raise
            if proc.returncode == 0:
                break
        sent = np.array([v[:3] for _, v in dev.sent])
        events = {k for _, k in dev.events}
        # kept beside the recording: a failure below can be traced to the device's own log
        (tmp_path / "device.json").write_text(json.dumps({"sent": dev.sent, "events": dev.events}))
    assert proc.returncode == 0, proc.stderr.read().decode()[-2000:]
    assert kills == 3 and {"garbage", "partial", "drop"} <= events
    text = out.read_text()
    assert text.count("complete: step") == 2 * (1 + 2 * 4)          # every hold of the plan, once
    rec = read_recording(out)                                          # parses: no torn line left
    assert np.all(np.diff(rec.time_s) >= 0)
    # every recorded reading is one the device sent (device units: um with 4 decimals), none twice, in the order
    # sent. The gauges resolve 1 um, so equal readings are common: each row is matched under the zero in effect
    # where it stands in the file (a series killed after its zero and redone has two), to the earliest reading
    # sent after the previous row's.
    sent_order, last = [], -1
    for i, zero in enumerate(_zero_of_each_row(text, rec)):
        comps = [c for c in range(3) if np.isfinite(rec.disp_mm[i, c])]
        raw = (rec.disp_mm[i] + zero)[comps] * 1e3
        hits = np.nonzero(np.abs(sent[:, comps] - raw).max(axis=1) < 2e-3)[0]
        assert hits.size, f"row {i} was never sent by the device"
        later = hits[hits > last]
        assert later.size, f"row {i} duplicates a reading already recorded (or is out of order)"
        last = int(later[0])
        sent_order.append(last)
    matched = np.zeros(len(sent), dtype=bool)
    matched[sent_order] = True
    stats = {"kills": kills, "runs": runs, "rows": int(rec.n), "sent": int(len(sent)),
             "sent_not_recorded": int((~matched).sum()), "faults": sorted(events)}
    (tmp_path / "soak.json").write_text(json.dumps(stats))
    print(stats)
