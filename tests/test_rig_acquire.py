"""Acquisition over a real pseudo-terminal (pyserial against the simulator, no mocks)."""
from __future__ import annotations

import contextlib
from pathlib import Path

import numpy as np
import pytest

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method
from rodlab.stiffness_rig import DeviceError, RigError, fit_recording, read_recording
from rodlab.stiffness_rig.acquire import RecordingLock, acquire
from rodlab.stiffness_rig.config import Channel, RigPlan, RigProfile
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simdevice import Faults, SimulatedRig
from rodlab.stiffness_rig.simulate import simulate_recording

ROOT_DATA = Path(__file__).resolve().parents[1] / "stiffness_rig" / "plans"
C = np.array([[0.0063, 0.0, -0.0151], [0.0, 0.2198, 0.0], [-0.0151, 0.0, 0.0666]])
SIM = RodCompliance("1#", Method.CALC, C, 1.2 * C, 0.46, np.zeros(3), np.array([450.0, 0, 300]))


def _profile(port, protocol="query", checksum="none", retries=5):
    return RigProfile(port=port, protocol=protocol, checksum=checksum, retries=retries, timeout_s=0.2,
                      channels=tuple(Channel(i, i, 1.0, 0.001) for i in range(3)), temperature_index=3,
                      loader_command="LOAD {axis} {phase} {mass_kg:.4f}\r\n")


def _plan(axes=("y", "z"), masses=(1.0, 2.0), repeats=1, hold_s=0.5):
    return RigPlan("1#", LoadSchedule(axes=axes, masses=masses, repeats=repeats, hold_s=hold_s, rate_Hz=20.0),
                   settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=3.0)


def test_acquisition_with_faults_recovers_compliance(tmp_path):
    model = RigModel(C, {"friction": {"F_f_N": 0.2}}, seed=4)
    with SimulatedRig(model, tmp_path / "tty", faults=Faults(garbage=0.08, drop=0.05, partial=0.05), seed=2) as dev:
        statuses = []
        out = acquire(_profile(dev.port), _plan(repeats=2), tmp_path / "r.rig.csv", use_loader=True,
                      progress=statuses.append)
        kinds = {k for _, k in dev.events}
        drops = sum(k == "drop" for _, k in dev.events)
    rec = read_recording(out)
    assert {"garbage", "drop", "partial"} <= kinds
    assert statuses[-1].timeouts >= drops > 0           # each dropped answer counted (the CLI says how many)
    assert np.all(np.diff(rec.time_s) >= 0)
    assert rec.n <= len(dev.sent)                       # nothing invented
    fit = fit_recording(rec, SIM)
    assert fit.C_F_meas[1, 1] == pytest.approx(C[1, 1], rel=0.01)
    assert fit.C_F_meas[2, 2] == pytest.approx(C[2, 2], rel=0.01)
    for ln in fit.lines:
        if ln.component == ln.axis.index:
            assert ln.zero_load_kg["load"] == pytest.approx(0.2 / 9.80665, rel=0.2)


@contextlib.contextmanager
def _interrupted(tmp_path, holds: int):
    """A simulated rig whose acquisition of the plan into r.rig.csv was stopped (Ctrl-C) once ``holds`` holds were
    complete; yields (model, profile, plan, output) with the rig still attached."""
    model = RigModel(C, seed=5)
    out = tmp_path / "r.rig.csv"
    plan = _plan()
    with SimulatedRig(model, tmp_path / "tty") as dev:
        prof = _profile(dev.port)

        def stop(st):
            if st.holds_done == holds:
                raise KeyboardInterrupt
        with pytest.raises(KeyboardInterrupt):
            acquire(prof, plan, out, use_loader=True, progress=stop)
        yield model, prof, plan, out


def test_interrupted_acquisition_resumes_without_losing_samples(tmp_path):
    with _interrupted(tmp_path, 3) as (model, prof, plan, out):
        before = out.read_bytes()
        part = read_recording(out)
        acquire(prof, plan, out, use_loader=True)
    after = out.read_bytes()
    assert after.startswith(before)                       # nothing already recorded changed
    rec = read_recording(out)
    assert rec.n > part.n and np.all(np.diff(rec.time_s) > 0)
    assert len(rec.steps()) == len(plan.schedule.holds())
    assert out.read_text().count("complete: step") == len(plan.schedule.holds())
    # a finished plan is not recorded again
    size = out.stat().st_size
    with SimulatedRig(model, tmp_path / "tty") as dev:
        acquire(_profile(dev.port), plan, out, use_loader=True)
    assert out.stat().st_size == size
    assert not (tmp_path / "r.rig.csv.lock").exists()       # the lock goes with the run


@pytest.mark.parametrize("change,key,named", [
    (lambda prof, plan: (prof, RigPlan("1#", LoadSchedule(axes=("y",), masses=(2.0,), repeats=1, hold_s=0.5, rate_Hz=20.0),
                                       settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=3.0)),
     "plan_hash", "holds.count 10 -> 3, holds from number 2 on"),
    (lambda prof, plan: (prof, RigPlan("1#", LoadSchedule(axes=("y", "z"), masses=(1.0, 2.0), repeats=1, hold_s=0.5,
                                                      rate_Hz=10.0))), "sample_rate_Hz", None),
    (lambda prof, plan: (RigProfile(**{**prof.__dict__, "port": prof.port + "-other"}), plan), "device", None),
    (lambda prof, plan: (RigProfile(**{**prof.__dict__, "channels": tuple(Channel(i, i, -1.0, 0.001)
                                                                           for i in range(3))}), plan), "device_hash",
     "channels number 1, 2, 3"),
    (lambda prof, plan: (prof, RigPlan("1#", LoadSchedule(axes=("y", "z"), masses=(1.0, 2.0), repeats=1, hold_s=1.5,
                                                          rate_Hz=20.0), settle_window_s=0.25,
                                       settle_tolerance_mm=0.004, settle_timeout_s=3.0)),
     "plan_hash", "(changed: hold_s 0.5 -> 1.5)"),
], ids=["other plan", "other rate", "other port", "other wiring", "other hold time"])
def test_resume_with_another_plan_rate_or_device_is_refused(tmp_path, change, key, named):
    """A re-run into a partly recorded file with another plan, rate or device changes nothing on disk and says
    what to do; the same plan resumes after the last complete hold."""
    from rodlab.stiffness_rig.resume import resume_point
    model, out, plan = RigModel(C, seed=8), tmp_path / "r.rig.csv", _plan()

    def stop_after_two(st):
        if st.holds_done == 2:
            raise KeyboardInterrupt
    with SimulatedRig(model, tmp_path / "tty") as dev:
        prof = _profile(dev.port)
        with pytest.raises(KeyboardInterrupt):
            acquire(prof, plan, out, use_loader=True, progress=stop_after_two)
        recorded = out.read_bytes()
        prof2, plan2 = change(prof, plan)
        with pytest.raises(RigError) as ei:
            acquire(prof2, plan2, out, use_loader=True)
        assert ei.value.key == key and str(out) in str(ei.value) and "--new-file" in str(ei.value)
        assert named is None or named in str(ei.value)          # the part that changed is named
        assert out.read_bytes() == recorded and not (tmp_path / "r.rig.csv.lock").exists()
        start = resume_point(out, prof, plan)
        assert (start.holds_done, start.holds_total, start.resuming) == (2, len(plan.schedule.holds()), True)


def test_failed_port_open_leaves_nothing_behind(tmp_path):
    out = tmp_path / "r.rig.csv"
    with pytest.raises(DeviceError, match="cannot open"):
        acquire(_profile(str(tmp_path / "no-such-tty")), _plan(), out, use_loader=True)
    assert sorted(tmp_path.iterdir()) == []


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


def _write_plan(path, masses, rate_Hz):
    path.write_text(f'format = "rodlab.rigplan/1"\nrod = "1#"\naxes = ["y"]\nmasses_kg = {list(masses)}\nrepeats = 1\n'
                    f'hold_s = 0.3\nrate_Hz = {rate_Hz}\n[settle]\nwindow_s = 0.2\ntolerance_mm = 0.004\n'
                    f'timeout_s = 3.0\n')
    return path


def test_cli_resume_refusal_new_file_and_simulator_cleanup(tmp_path, capsys):
    """The console says where a resume starts; another plan is refused with exit 2 naming --new-file; --new-file
    records beside the file; a simulator ended by SIGTERM removes its pty link."""
    import os
    import signal
    import subprocess
    import sys
    import time

    from rodlab.app.cli import main
    from rodlab.core.compliance import write_compliance
    from rodlab.stiffness_rig.config import read_plan, read_profile
    link = tmp_path / "tty"
    sim = write_compliance(SIM, tmp_path / "sim.compliance.json")
    server = subprocess.Popen([sys.executable, "-m", "rodlab", "rig", "simulator", "--sim", str(sim), "--link", str(link),
                               "--garbage", "0.05"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        for _ in range(200):
            if link.is_symlink():
                break
            time.sleep(0.05)
        profile = tmp_path / "rig.profile.toml"
        text = (ROOT_DATA / "simulator.profile.toml").read_text().replace('"/tmp/rodlab-rig"', f'"{link}"')
        profile.write_text(text)
        plan = _write_plan(tmp_path / "a.plan.toml", (1.0, 2.0), 20.0)
        out = tmp_path / "r.rig.csv"

        def stop_after_two(st):
            if st.holds_done == 2:
                raise KeyboardInterrupt
        with pytest.raises(KeyboardInterrupt):
            acquire(read_profile(profile), read_plan(plan), out, use_loader=True, progress=stop_after_two)
        n_holds = len(read_plan(plan).schedule.holds())
        args = ["rig", "acquire", "--profile", str(profile), "-o", str(out), "--non-interactive", "-q"]
        other = _write_plan(tmp_path / "b.plan.toml", (1.0, 2.0), 10.0)
        recorded = out.read_bytes()
        assert main([*args, "--plan", str(other)]) == 2
        err = capsys.readouterr().err
        assert "sample_rate_Hz" in err and "--new-file" in err and str(out) in err
        assert out.read_bytes() == recorded
        with RecordingLock(out):                   # another acquisition at work: named, no "resuming" said first
            assert main([*args, "--plan", str(plan)]) == 2
            said = capsys.readouterr()
            assert "another acquisition" in said.err and "resuming" not in said.out
        assert main([*args, "--plan", str(plan)]) == 0
        said = capsys.readouterr().out
        assert f"resuming after hold 2/{n_holds}" in said
        assert "garbage line(s) (skipped)" in said                # the run's garbage said once at its end
        assert main([*args, "--plan", str(other), "--new-file"]) == 0
        assert "recording into" in capsys.readouterr().out
        assert read_recording(tmp_path / "r-2.rig.csv").meta["sample_rate_Hz"] == "10"
        assert out.read_text().count("complete: step") == n_holds
        assert not list(tmp_path.glob("*.lock"))
    finally:
        server.send_signal(signal.SIGTERM)
        server.wait(timeout=10)
    assert server.returncode == 0 and not os.path.lexists(link)


def test_a_sample_cut_off_mid_line_is_left_out_and_the_acquisition_resumes(tmp_path, caplog):
    """Power lost while a line was written: the file ends in part of a sample. Reading it leaves that line out
    with a warning naming it; re-running the acquisition resumes (the writer drops the partial line first)."""
    with _interrupted(tmp_path, 2) as (model, prof, plan, out):
        whole = read_recording(out)
        text = out.read_text()
        out.write_text(text + text.splitlines()[-1 if text.splitlines()[-1][:1].isdigit() else -2][:25])
        lines = out.read_text().splitlines()
        with caplog.at_level("WARNING"):
            cut = read_recording(out)
        assert cut.n == whole.n and f"line {len(lines)}: the last line has" in caplog.text
        acquire(prof, plan, out, use_loader=True)
    rec = read_recording(out)
    assert len(rec.steps()) == len(plan.schedule.holds()) and np.all(np.diff(rec.time_s) > 0)


def test_a_file_cut_during_its_first_sample_resumes(tmp_path):
    """The power failed while the first sample was written: the file ends in part of it, with no complete sample;
    the acquisition starts again after the header (nothing is lost: there was nothing)."""
    from rodlab.stiffness_rig.resume import resume_point
    with _interrupted(tmp_path, 1) as (model, prof, plan, out):
        lines = out.read_text().splitlines(True)
        first = next(i for i, ln in enumerate(lines) if ln[:1].isdigit())
        out.write_text("".join(lines[:first]) + lines[first][:20])
        assert resume_point(out, prof, plan).holds_done == 0
        acquire(prof, plan, out, use_loader=True)
    rec = read_recording(out)
    assert len(rec.steps()) == len(plan.schedule.holds())


def test_a_hold_comment_cut_off_is_not_taken_for_a_complete_hold(tmp_path):
    """Power lost while the comment after the last hold was written ("# hold 2/N complete: step 1" of "step 12"):
    that torn line matches the pattern of a complete hold, but the writer drops it, so the resume starts at that
    hold again instead of skipping it (the file would have lacked its comment)."""
    from rodlab.stiffness_rig.resume import resume_point
    with _interrupted(tmp_path, 2) as (model, prof, plan, out):
        text = out.read_text()
        done = resume_point(out, prof, plan).holds_done
        out.write_text(text + f"# hold {done + 1}/{len(plan.schedule.holds())} complete: step 1")
        assert resume_point(out, prof, plan).holds_done == done
        acquire(prof, plan, out, use_loader=True)
    text = out.read_text()
    assert all(text.count(f"# hold {k}/") == 1 for k in range(1, len(plan.schedule.holds()) + 1))


@pytest.mark.parametrize("edit,message", [
    (lambda t: t.replace(",", ";"), "separated by semicolons, not commas"),
    (lambda t: t.replace(",", "\t"), "separated by tabs, not commas"),
    (lambda t: t + t[t.index("time_s"):], "repeats the header: two recordings joined"),
    (lambda t: t + t[t.index("time_s"):].replace(",temp_C", "").replace(",21.0", ","),     # without temperatures
     "repeats the header: two recordings joined"),
    (lambda t: "\n".join(t.splitlines()[:-3] + [t.splitlines()[-2][:8], t.splitlines()[-1]]) + "\n",
     "expected 10 cells, got 2"),                         # a cut line inside the file is an error, not dropped
])
def test_damaged_recordings_say_what_happened(tmp_path, edit, message):
    path = tmp_path / "r.rig.csv"
    simulate_recording(RigModel(C, seed=1), LoadSchedule(axes=("y",), masses=(1.0,), repeats=1, hold_s=1.0), path,
                       rod="1#")
    path.write_text(edit(path.read_text()))
    with pytest.raises(RigError, match=message):
        read_recording(path)


def test_a_plan_that_records_other_gauges_is_another_plan_to_a_resume():
    """The schedule's default components and the same plan listing them in [measured] record different gauges
    under a z load (every gauge against x and z): a resume must not join them (review)."""
    import dataclasses

    from rodlab.stiffness_rig.resume import plan_hash
    plan = _plan(axes=("z",))
    stated = dataclasses.replace(plan, measured_stated=frozenset({"z"}))
    assert plan.recorded("z") != stated.recorded("z")
    assert plan_hash(plan) != plan_hash(stated)
    assert plan_hash(plan) == plan_hash(dataclasses.replace(plan))
