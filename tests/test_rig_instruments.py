"""Several instruments, each on its own pty with its own protocol (pyserial against the simulators, no mocks):
every driver of the registry end to end with garbage, stalls and a replug, a mixed rig (two Digimatic
indicators + a Modbus load cell) that fits the truth and measures the slides' friction, resume, profile errors."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from conftest import legacy_design
from rodlab import calc_rod_compliance
from rodlab.stiffness_rig import DeviceError, RigError, fit_recording, read_recording
from rodlab.stiffness_rig.acquire import acquire
from rodlab.stiffness_rig.config import RigPlan, read_profile
from rodlab.stiffness_rig.drivers import DRIVERS
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig import siminstruments as si
from rodlab.stiffness_rig.siminstruments import Faults, SimBench

PLANS = Path(__file__).resolve().parents[1] / "stiffness_rig" / "plans"
SIM = calc_rod_compliance(legacy_design("rod1"))     # the rod 1# the rig machinery was sized on (conftest)
C = SIM.C_F
FAULTS = Faults(garbage=0.05, stall=0.02, stall_s=0.4, disconnect=0.01, reconnect_after_s=0.2)
LOADER = '[loader]\ninstrument = "{who}"\ncommand = "LOAD {{axis}} {{phase}} {{mass_kg:.4f}}\\r\\n"\n'


def _plan(axes=("y", "z"), repeats=1, masses=(1.0, 2.0)):
    return RigPlan("1#", LoadSchedule(axes=axes, masses=masses, repeats=repeats, hold_s=0.5, rate_Hz=20.0),
                   settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=3.0)


def _instrument(name, port, protocol, channels, **settings) -> str:
    lines = [f'[[instrument]]\nname = "{name}"\nport = "{port}"\nprotocol = "{protocol}"\ntimeout_s = 0.2']
    for k, v in settings.items():
        if k == "registers":
            continue
        lines.append(f"{k} = {v!r}" if not isinstance(v, str) else f'{k} = "{v}"')
    for reg in settings.get("registers", []):
        lines.append("[[instrument.registers]]\n" + "\n".join(
            f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v}" for k, v in reg.items()))
    for ch in channels:
        lines.append("[[instrument.channel]]\n" + "\n".join(
            f'{k} = "{v}"' if isinstance(v, str) else f"{k} = {v}" for k, v in ch.items()))
    return "\n".join(lines) + "\n"


def _profile(tmp_path, body: str, loader: str | None) -> Path:
    p = tmp_path / "rig.profile.toml"
    p.write_text('format = "rodlab.rigprofile/2"\n' + body + (LOADER.format(who=loader) if loader else ""))
    return p


def _gauges(tmp_path, bench, faults=FAULTS):
    """Two Digimatic indicators on y and z (the z one mounted upside down: sign -1)."""
    y = si.SimDigimatic(bench, tmp_path / "ttyY", faults=faults, seed=1, axis="y")
    z = si.SimDigimatic(bench, tmp_path / "ttyZ", faults=faults, seed=2, axis="z", sign=-1.0)
    body = (_instrument("dial_y", y.port, "digimatic", [{"quantity": "displacement", "axis": "y"}])
            + _instrument("dial_z", z.port, "digimatic", [{"quantity": "displacement", "axis": "z", "sign": -1}]))
    return [y, z], body


def _run(tmp_path, devices, profile_path, plan=None, out_name="r.rig.csv"):
    for d in devices:
        d.start()
    try:
        out = acquire(read_profile(profile_path), plan or _plan(), tmp_path / out_name, use_loader=True)
    finally:
        for d in devices:
            d.stop()
    return read_recording(out)


def _check_fit(rec, rel=0.01):
    fit = fit_recording(rec, SIM)
    assert fit.C_F_meas[1, 1] == pytest.approx(C[1, 1], rel=rel)
    assert fit.C_F_meas[2, 2] == pytest.approx(C[2, 2], rel=rel)
    return fit


def test_every_driver_has_a_simulator_and_settings():
    for name, cls in DRIVERS.items():
        assert cls.name == name and cls.summary and hasattr(si, cls.simulator), name


def test_mixed_rig_two_digimatic_and_a_modbus_load_cell(tmp_path):
    """The paper's rig with a load cell: two Digimatic indicators on two ports and a Modbus RTU load cell on a
    third, slides with 0.3 N of friction, garbage / stalls / replugs on every port. The recording has force_N;
    the fit is the truth without any friction hypothesis and the friction per branch is within 10 %."""
    model = RigModel(C, {"friction": {"F_f_N": 0.3}}, seed=2, load_cell_noise_N=0.005)
    bench = SimBench(model)
    gauges, body = _gauges(tmp_path, bench)
    cell = si.SimModbusRTU(bench, tmp_path / "ttyF", faults=FAULTS, seed=3)
    body += _instrument("load_cell", cell.port, "modbus_rtu", [{"quantity": "force", "value": "force"}], slave=1,
                        registers=[{"name": "force", "address": 0, "type": "float32"}])
    rec = _run(tmp_path, [*gauges, cell], _profile(tmp_path, body, "dial_y"))
    kinds = {k for d in (*gauges, cell) for _, k in d.events}
    assert {"garbage", "stall", "disconnect"} <= kinds, kinds
    assert rec.has_force and np.isfinite(rec.force_N).all()
    fit = _check_fit(rec)
    for ln in fit.lines:
        if ln.component == ln.axis.index:                       # the branches meet: friction is in the force
            assert abs(ln.zero_load_kg["load"] - ln.zero_load_kg["unload"]) < 0.1 * 0.3 / 9.80665
    for axis, ff in fit.load.friction_N.items():
        assert ff == pytest.approx(0.3, rel=0.10), axis
    for b in fit.load.branches:
        assert b.diff_N == pytest.approx(0.3 if b.phase.value == "load" else -0.3, rel=0.10), b
    text = (tmp_path / "r.rig.csv").read_text()
    assert "# instruments step" in text and "+ " in text.split("# device:")[1].splitlines()[0]


@pytest.mark.parametrize("kind", ["int32_little_input", "int16_holding"])
def test_modbus_register_types(tmp_path, kind):
    """int32 in mN with the low word first from input registers, and int16 in 0.01 N from holding registers:
    the force recorded is the load cell's within its resolution."""
    model = RigModel(C, seed=4, load_cell_noise_N=0.0)
    bench = SimBench(model)
    gauges, body = _gauges(tmp_path, bench, Faults())
    if kind == "int32_little_input":
        regs = {7: ("force_N", "int32", "little", 4, 1000.0)}
        reg = {"name": "f", "address": 7, "function": 4, "type": "int32", "word_order": "little", "scale": 0.001}
        tol = 1e-3
    else:
        regs = {3: ("force_N", "int16", "big", 3, 100.0)}
        reg = {"name": "f", "address": 3, "type": "int16", "scale": 0.01}
        tol = 0.01
    cell = si.SimModbusRTU(bench, tmp_path / "ttyF", seed=5, slave=7, registers=regs)
    body += _instrument("cell", cell.port, "modbus_rtu", [{"quantity": "force", "value": "f"}], slave=7,
                        registers=[reg])
    rec = _run(tmp_path, [*gauges, cell], _profile(tmp_path, body, "dial_y"), _plan(axes=("y",), masses=(2.0,)))
    loaded = rec.mass_kg == 2.0
    np.testing.assert_allclose(rec.force_N[loaded], 2.0 * 9.80665, atol=tol + 1e-9)
    np.testing.assert_allclose(rec.force_N[rec.mass_kg == 0], 0.0, atol=tol + 1e-9)


def test_ascii_regex_controller_with_two_outputs(tmp_path):
    """A sensor controller answering 'M0,<y um>,<z um>' on one port: one request, two channels in um, faults."""
    bench = SimBench(RigModel(C, seed=6))
    ctl = si.SimAsciiRegex(bench, tmp_path / "ttyC", faults=FAULTS, seed=7, template="M0,{y_um:+.3f},{z_um:+.3f}",
                           request="M0")
    body = _instrument("ctl", ctl.port, "ascii_regex",
                       [{"quantity": "displacement", "axis": "y", "value": "out1", "units": "um"},
                        {"quantity": "displacement", "axis": "z", "value": "out2", "units": "um"}],
                       request="M0\\r", pattern=r"^M0,(?P<out1>[-+0-9.]+),(?P<out2>[-+0-9.]+)$")
    rec = _run(tmp_path, [ctl], _profile(tmp_path, body, "ctl"))
    assert {k for _, k in ctl.events} & {"garbage", "stall", "disconnect"}
    _check_fit(rec)


def test_numeric_line_stream_with_checksum_and_a_thermometer(tmp_path):
    """rodlab's original line protocol as a driver: a streaming counter with XOR checksums (gauges in um and
    the temperature) beside a Digimatic indicator on another port."""
    bench = SimBench(RigModel(C, seed=8))
    counter = si.SimNumericLine(bench, tmp_path / "ttyN", faults=Faults(garbage=0.05, stall=0.02), seed=9,
                                fields=("y_um", "temp_C"), stream=True, checksum="xor")
    counter.rate_Hz = 40.0
    z = si.SimDigimatic(bench, tmp_path / "ttyZ", faults=FAULTS, seed=10, axis="z")
    body = (_instrument("counter", counter.port, "numeric_line",
                        [{"quantity": "displacement", "axis": "y", "value": 0, "units": "um"},
                         {"quantity": "temperature", "value": 1}], mode="stream", checksum="xor")
            + _instrument("dial_z", z.port, "digimatic", [{"quantity": "displacement", "axis": "z"}]))
    rec = _run(tmp_path, [counter, z], _profile(tmp_path, body, "dial_z"))
    assert rec.temp_C is not None and np.all(np.abs(rec.temp_C - 21.0) < 1.5)
    _check_fit(rec, rel=0.02)


def test_resume_with_several_instruments_loses_nothing(tmp_path):
    bench = SimBench(RigModel(C, seed=11))
    gauges, body = _gauges(tmp_path, bench, Faults())
    profile = read_profile(_profile(tmp_path, body, "dial_y"))
    plan, out = _plan(), tmp_path / "r.rig.csv"

    def stop_after_three(st):
        if st.holds_done == 3:
            raise KeyboardInterrupt
    for d in gauges:
        d.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            acquire(profile, plan, out, use_loader=True, progress=stop_after_three)
        before = out.read_bytes()
        acquire(profile, plan, out, use_loader=True)
    finally:
        for d in gauges:
            d.stop()
    assert out.read_bytes().startswith(before)
    rec = read_recording(out)
    # in time order (two readings of one millisecond share a time stamp on a busy machine)
    assert len(rec.steps()) == len(plan.schedule.holds()) and np.all(np.diff(rec.time_s) >= 0)
    rewired = _profile(tmp_path, body.replace('"z"\nsign = -1', '"x"\nsign = -1'), "dial_y")
    with pytest.raises(RigError, match="device wiring"):
        acquire(read_profile(rewired), plan, out, use_loader=True)


def test_an_instrument_that_answers_nothing_usable(tmp_path):
    """A gauge whose every answer is garbage: retried, its port reopened, then a clear error naming it; what
    was recorded before stays."""
    bench = SimBench(RigModel(C, seed=12))
    gauges, body = _gauges(tmp_path, bench, Faults())
    for d in gauges:
        d.start()
    from rodlab.stiffness_rig.instruments import RigClient
    try:
        client = RigClient(read_profile(_profile(tmp_path, body, "dial_y")), reconnect_attempts=2)
        client.read_sample()
        gauges[1].faults = Faults(garbage=1.0)
        with pytest.raises(DeviceError, match="'dial_z'.*nothing usable"):
            client.read_sample()
        client.close()
    finally:
        for d in gauges:
            d.stop()


PROFILE_ERRORS = [
    ("unknown protocol", {"protocol": "keyence"}, "instrument", "keyence"),
    ("regex without pattern", {"protocol": "ascii_regex"}, "instrument[1].pattern", "needs `pattern`"),
    ("value not given", {"value": "force"}, "instrument[1].channel[1].value", "gives the values ['value']"),
    ("axis of a force", {"quantity": "force", "axis": "y"}, "instrument[1].channel[1].axis", "only a displacement"),
    ("bad units", {"units": "N"}, "instrument[1].channel[1].units", "units"),
]


@pytest.mark.parametrize("label,change,key,words", PROFILE_ERRORS, ids=[e[0] for e in PROFILE_ERRORS])
def test_profile_errors_name_the_key(tmp_path, label, change, key, words):
    ins = {"protocol": "digimatic"}
    ch = {"quantity": "displacement", "axis": "y"}
    for k, v in change.items():
        (ins if k == "protocol" else ch)[k] = v
    body = _instrument("dial", "/dev/null", ins["protocol"], [ch])
    with pytest.raises(RigError) as ei:
        read_profile(_profile(tmp_path, body, None))
    assert ei.value.key.startswith(key) and words in str(ei.value), str(ei.value)
    if label == "bad units":                         # the reader names the channel's own line, as validate does
        text = (tmp_path / "rig.profile.toml").read_text().splitlines()
        assert text[ei.value.line - 1].strip().startswith("units")


def test_modbus_and_loader_errors(tmp_path):
    body = _instrument("cell", "/dev/null", "modbus_rtu", [{"quantity": "force", "value": "f"}],
                       registers=[{"name": "f", "address": 0, "type": "float64"}])
    with pytest.raises(RigError, match="float32") as ei:
        read_profile(_profile(tmp_path, _instrument("d", "/dev/null", "digimatic",
                                                     [{"quantity": "displacement", "axis": "y"}]) + body, None))
    assert ei.value.key == "instrument[2].registers[0].type"
    good = body.replace("float64", "float32")
    with pytest.raises(RigError, match="text-protocol") as ei:
        read_profile(_profile(tmp_path, _instrument("d", "/dev/null", "digimatic",
                                                     [{"quantity": "displacement", "axis": "y"}]) + good, "cell"))
    assert ei.value.key == "loader.instrument"


def test_example_profiles_read_and_validate():
    """Every example profile in stiffness_rig/plans reads (v1 and v2) and passes rodlab validate."""
    from rodlab.app.cli.cmd_validate import validate_file
    found = sorted(PLANS.glob("*.profile.toml"))
    assert len(found) >= 5
    for p in found:
        read_profile(p)
        assert validate_file(p).ok, (p, validate_file(p).problems)


def test_cli_simulator_serves_an_example_profile(tmp_path):
    """rodlab rig simulator --profile serves every instrument of an example profile under --link-dir and
    writes the profile pointed at them; an acquisition from it records force_N; SIGTERM removes the links."""
    import signal
    import subprocess
    import sys
    import time

    from rodlab import write_compliance
    sim = write_compliance(SIM, tmp_path / "sim.compliance.json")
    links = tmp_path / "links"
    server = subprocess.Popen([sys.executable, "-m", "rodlab", "rig", "simulator", "--sim", str(sim), "--profile",
                               str(PLANS / "two-digimatic-loadcell.profile.toml"), "--link-dir", str(links),
                               "--effect", "friction:F_f_N=0.5"], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        for _ in range(200):
            if (links / "load_cell").is_symlink():
                break
            time.sleep(0.05)
        profile = read_profile(links / "sim.profile.toml")    # with the [loader] the simulator added
        assert profile.loader_instrument == "dial_y"
        assert [i.port for i in profile.instruments] == [str(links / n) for n in ("dial_y", "dial_z", "load_cell")]
        out = acquire(profile, _plan(axes=("y",)), tmp_path / "r.rig.csv", use_loader=True)
    finally:
        server.send_signal(signal.SIGTERM)
        server.wait(timeout=10)
    rec = read_recording(out)
    fit = fit_recording(rec)
    assert fit.C_F_meas[1, 1] == pytest.approx(C[1, 1], rel=0.01)
    assert fit.load.friction_N[next(iter(fit.load.friction_N))] == pytest.approx(0.5, rel=0.1)
    assert not any(p.is_symlink() for p in links.iterdir())


def test_docs_table_of_protocols_comes_from_the_registry():
    from rodlab.stiffness_rig.drivers import drivers_markdown
    doc = (Path(__file__).resolve().parents[1] / "docs" / "rig.md").read_text()
    assert drivers_markdown() in doc


def test_commanding_a_loader_the_profile_lacks_writes_nothing(tmp_path):
    profile = read_profile(PLANS / "two-digimatic.profile.toml")
    with pytest.raises(RigError, match="no \\[loader\\]"):
        acquire(profile, _plan(), tmp_path / "r.rig.csv", use_loader=True)
    assert sorted(tmp_path.iterdir()) == []


@pytest.mark.parametrize("pattern", [r"^G1\s+(?P<out1>[-+]?\d+\.\d+)\s*(mm|MM)$", r"^ST,GS,(?P<out1>[-+0-9.]+) ?kgf$",
                                     r"^\[(?P<out1>-?\d+\.\d{3})\]{1,2}[^,]*$"])
def test_the_simulator_answers_in_the_form_of_any_pattern(pattern):
    """The simulated controller's answers match its profile's pattern however it is written (escapes, optional
    spaces, alternations, classes): a new-user trial's ``\\s+`` and ``(mm|MM)`` had been sent literally."""
    from rodlab.stiffness_rig.regex_template import template_of
    template = template_of(pattern)
    for v in (-0.0567, 0.0, 1.25):
        m = re.search(pattern, template.format(out1=v))
        assert m and float(m.group("out1")) == pytest.approx(v, abs=1e-3)


def test_a_pattern_the_simulator_cannot_answer_is_named():
    from rodlab.stiffness_rig.regex_template import template_of
    with pytest.raises(RigError, match="cannot answer in the form of pattern"):
        template_of(r"^(?P<out1>\d+)(?P=out1)$", key="instruments.ctl.pattern")


def test_a_profile_with_a_spaced_pattern_acquires_on_its_simulator(tmp_path):
    bench = SimBench(RigModel(C, seed=8))
    links = {"ctl": tmp_path / "ttyC"}
    body = _instrument("ctl", links["ctl"], "ascii_regex",
                       [{"quantity": "displacement", "axis": "y", "value": "out1", "units": "mm"},
                        {"quantity": "displacement", "axis": "z", "value": "out2", "units": "mm"}],
                       request="M0\\r",
                       pattern=r"^M0\s+(?P<out1>[-+]?\d+\.\d+)\s*;\s*(?P<out2>[-+]?\d+\.\d+)\s*(mm|MM)$".replace("\\", "\\\\"))
    profile = _profile(tmp_path, body, "ctl")
    devices = si.simulators_for(read_profile(profile), bench, links)
    _check_fit(_run(tmp_path, devices, profile))


def test_acquire_without_a_terminal_is_refused_before_any_file_is_made(tmp_path, capsys):
    """Without --non-interactive nobody can be prompted to hang the weights: refused up front, no header-only
    recording left behind (new-user trial)."""
    from rodlab.app.cli import main
    out = tmp_path / "lab.rig.csv"
    assert main(["rig", "acquire", "--profile", str(PLANS / "two-digimatic.profile.toml"), "--plan",
                 str(PLANS / "quick.plan.toml"), "-o", str(out)]) == 2
    assert "no terminal" in capsys.readouterr().err
    assert not out.exists()
