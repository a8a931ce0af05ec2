"""Acquisition over a real pseudo-terminal (pyserial against the simulator, no mocks)."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.compliance import RodCompliance
from rodlab.enums import Method
from rodlab.stiffness_rig import DeviceError, RigError, fit_recording, read_recording
from rodlab.stiffness_rig.acquire import RecordingLock, acquire
from rodlab.stiffness_rig.config import Channel, RigPlan, RigProfile
from rodlab.stiffness_rig.model import Protocol, RigModel
from rodlab.stiffness_rig.simdevice import Faults, SimulatedRig

C = np.array([[0.0063, 0.0, -0.0151], [0.0, 0.2198, 0.0], [-0.0151, 0.0, 0.0666]])
SIM = RodCompliance("1#", Method.CALC, C, 1.2 * C, 0.46, np.zeros(3), np.array([450.0, 0, 300]))


def _profile(port, protocol="query", checksum="none", retries=5):
    return RigProfile(port=port, protocol=protocol, checksum=checksum, retries=retries, timeout_s=0.2,
                      channels=tuple(Channel(i, i, 1.0, 0.001) for i in range(3)), temperature_index=3,
                      loader_command="LOAD {axis} {phase} {mass_kg:.4f}\r\n")


def _plan(axes=("y", "z"), masses=(1.0, 2.0), repeats=1, hold_s=0.5):
    return RigPlan("1#", Protocol(axes=axes, masses=masses, repeats=repeats, hold_s=hold_s, rate_Hz=20.0),
                   settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=3.0)


def test_acquisition_with_faults_recovers_compliance(tmp_path):
    model = RigModel(C, {"friction": {"F_f_N": 0.2}}, seed=4)
    with SimulatedRig(model, tmp_path / "tty", faults=Faults(garbage=0.08, drop=0.05, partial=0.05), seed=2) as dev:
        out = acquire(_profile(dev.port), _plan(repeats=2), tmp_path / "r.rig.csv", use_loader=True)
        kinds = {k for _, k in dev.events}
    rec = read_recording(out)
    assert {"garbage", "drop", "partial"} <= kinds
    assert np.all(np.diff(rec.time_s) >= 0)
    assert rec.n <= len(dev.sent)                       # nothing invented
    fit = fit_recording(rec, SIM)
    assert fit.C_F_meas[1, 1] == pytest.approx(C[1, 1], rel=0.01)
    assert fit.C_F_meas[2, 2] == pytest.approx(C[2, 2], rel=0.01)
    for ln in fit.lines:
        if ln.component == ln.axis.index:
            assert ln.zero_load_kg["load"] == pytest.approx(0.2 / 9.80665, rel=0.2)


def test_interrupted_acquisition_resumes_without_losing_samples(tmp_path):
    model = RigModel(C, seed=5)
    out = tmp_path / "r.rig.csv"
    plan = _plan()
    with SimulatedRig(model, tmp_path / "tty") as dev:
        prof = _profile(dev.port)

        def stop_after_three(st):
            if st.holds_done == 3:
                raise KeyboardInterrupt
        with pytest.raises(KeyboardInterrupt):
            acquire(prof, plan, out, use_loader=True, progress=stop_after_three)
        before = out.read_bytes()
        part = read_recording(out)
        acquire(prof, plan, out, use_loader=True)
    after = out.read_bytes()
    assert after.startswith(before)                       # nothing already recorded changed
    rec = read_recording(out)
    assert rec.n > part.n and np.all(np.diff(rec.time_s) > 0)
    assert len(rec.steps()) == len(plan.protocol.holds())
    assert out.read_text().count("complete: step") == len(plan.protocol.holds())
    # a finished plan is not recorded again
    size = out.stat().st_size
    with SimulatedRig(model, tmp_path / "tty2") as dev:
        acquire(_profile(dev.port), plan, out, use_loader=True)
    assert out.stat().st_size == size


def test_second_process_is_refused(tmp_path):
    out = tmp_path / "r.rig.csv"
    with RecordingLock(out):
        with pytest.raises(RigError, match="another acquisition"):
            acquire(_profile("loop://"), _plan(), out, use_loader=True)


def test_device_that_stops_answering(tmp_path):
    model = RigModel(C, seed=6)
    dev = SimulatedRig(model, tmp_path / "tty").start()
    out = tmp_path / "r.rig.csv"

    def unplug(st):
        if st.holds_done == 2:
            dev.stop()
    with pytest.raises(DeviceError) as ei:
        acquire(_profile(dev.port, retries=2), _plan(), out, use_loader=True, progress=unplug)
    assert "re-run" in str(ei.value)
    rec = read_recording(out)
    assert out.read_text().count("complete: step") == 2 and rec.n > 0


def test_stream_protocol_with_checksums(tmp_path):
    model = RigModel(C, seed=7)
    with SimulatedRig(model, tmp_path / "tty", protocol="stream", checksum="xor", rate_Hz=20.0,
                      faults=Faults(garbage=0.05)) as dev:
        out = acquire(_profile(dev.port, "stream", "xor"), _plan(axes=("z",)), tmp_path / "s.rig.csv",
                      use_loader=True)
    fit = fit_recording(read_recording(out), None)
    assert fit.C_F_meas[2, 2] == pytest.approx(C[2, 2], rel=0.02)
