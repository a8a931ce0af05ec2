"""Gauge faults outside the effect vocabulary: a gauge at the end of its range and a gauge that slips once. Each is
``unexplained`` at its gauge and not read as rod or rig physics (a clipped gauge had been named a load
non-linearity with a joint and a tare; a slip a drift or a creep)."""
from __future__ import annotations

import pytest

from conftest import legacy_design, rewrite_recording
from rodlab import calc_rod_compliance
from rodlab.app.diagnose import diagnose_rig
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

DESIGN = legacy_design("rod1")
SIM = calc_rod_compliance(DESIGN)
SCHEDULE = LoadSchedule(repeats=3, hold_s=6.0)


def _recording(tmp_path, noise_mm=0.0006, resolution_mm=0.001, seed=21):
    model = RigModel(SIM.C_F, {}, noise_mm=noise_mm, resolution_mm=resolution_mm, seed=seed)
    return simulate_recording(model, SCHEDULE, tmp_path / "rec.rig.csv", rod=DESIGN.name)


def _clip_y(path, share: float):
    """(a copy of the recording ``path`` whose y gauge stops at +-``share`` of its largest reading, the stop [mm])."""
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    stop = round(share * max(abs(float(r[7])) for r in rows if r[7]), 4)

    def clip(_, row):
        if row["disp_y_mm"] and abs(float(row["disp_y_mm"])) > stop:
            row["disp_y_mm"] = f"{stop if float(row['disp_y_mm']) > 0 else -stop:.4f}"
    return rewrite_recording(path, path.with_name("clipped.rig.csv"), clip), stop


def _causes(diag) -> list:
    return [f for f in diag.findings if f.effect not in ("unexplained", "model_form")]


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_a_gauge_at_its_stop_is_unexplained_at_the_gauge_and_left_out(tmp_path, accuracy):
    """The y gauge clipped at 70 % of its largest reading (the two largest loads reach it and read alike): its
    holds at the stop are left out and named; nothing else is found."""
    clipped, stop = _clip_y(_recording(tmp_path), 0.7)
    diag, _ = diagnose_rig(read_recording(clipped), SIM, DESIGN, accuracy=accuracy)
    assert diag.verdict == "unexplained" and not _causes(diag), diag.summary()
    f = next(f for f in diag.findings if "range_limit_mm" in f.parameters)
    assert f.location == "sensor:y" and abs(f.parameters["range_limit_mm"]) == pytest.approx(stop)
    assert f.parameters["readings_left_out"] > 0


def test_a_coarse_gauge_on_a_quiet_rig_is_not_at_a_stop(tmp_path):
    """Noise a third of the resolution: a hold's readings mostly read one value, the largest load's too; that is
    no stop (every hold is alike), and the recording stays consistent."""
    diag, _ = diagnose_rig(read_recording(_recording(tmp_path, noise_mm=0.0003)), SIM, DESIGN, accuracy="exact")
    assert diag.verdict == "consistent", diag.summary()


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_a_gauge_that_slips_once_is_unexplained_at_the_gauge(tmp_path, accuracy):
    """The x gauge slips by 15 noise SDs halfway through the z series (to its end; the x series is zeroed
    again): named at the x gauge with the step, not a drift or a creep."""
    path = _recording(tmp_path, resolution_mm=0.0001)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    z_times = [float(r[0]) for r in rows if r[4] == "z"]
    t0, t1, step = 0.5 * (z_times[0] + z_times[-1]), z_times[-1], 0.009

    def slip(_, row):
        if row["disp_x_mm"] and t0 <= float(row["time_s"]) <= t1:
            row["disp_x_mm"] = f"{float(row['disp_x_mm']) + step:.5f}"
    slipped = rewrite_recording(path, tmp_path / "slipped.rig.csv", slip)
    diag, _ = diagnose_rig(read_recording(slipped), SIM, DESIGN, accuracy=accuracy)
    assert diag.verdict == "unexplained" and not _causes(diag), diag.summary()
    f = next(f for f in diag.findings if "slip_mm" in f.parameters)
    assert f.location == "sensor:x" and f.parameters["slip_mm"] == pytest.approx(step, rel=0.1)


def test_a_stop_the_largest_load_alone_reaches_is_found_by_its_missing_noise(tmp_path):
    """Clipped at 85 % of its largest reading, only the largest load's holds reach the stop (one load): they read
    one value without the noise the gauge's other holds show. Named, the whole holds left out, and the noise is
    that of the other readings (the stop's readings had pulled it down)."""
    clipped, _ = _clip_y(_recording(tmp_path), 0.85)
    diag, _ = diagnose_rig(read_recording(clipped), SIM, DESIGN, accuracy="exact")
    assert diag.verdict == "unexplained" and not _causes(diag), diag.summary()
    f = next(f for f in diag.findings if "range_limit_mm" in f.parameters)
    assert f.location == "sensor:y" and "without the noise" in f.explanation
    assert diag.noise_mm == pytest.approx(0.0006, rel=0.15)


def test_a_slip_in_a_negative_load_series_is_measured_in_that_series(tmp_path):
    """Series x and -x are zeroed apart: a slip in the second half of the x series ends with it, and is
    found at its size (it had run on into the -x series as one group and been half its size, or a drift)."""
    model = RigModel(SIM.C_F, {}, noise_mm=0.0006, resolution_mm=0.0001, seed=23)
    path = simulate_recording(model, LoadSchedule(axes=("x", "-x", "z"), repeats=3, hold_s=6.0),
                              tmp_path / "rec.rig.csv", rod=DESIGN.name)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    x_times = [float(r[0]) for r in rows if r[4] == "x"]
    t0, step = 0.5 * (x_times[0] + x_times[-1]), 0.009

    def slip(_, row):
        if row["load_axis"] == "x" and row["disp_x_mm"] and float(row["time_s"]) >= t0:
            row["disp_x_mm"] = f"{float(row['disp_x_mm']) + step:.5f}"
    slipped = rewrite_recording(path, tmp_path / "slipped.rig.csv", slip)
    for accuracy in ("exact", None):
        diag, _ = diagnose_rig(read_recording(slipped), SIM, DESIGN, accuracy=accuracy)
        assert not _causes(diag), diag.summary()
        f = next(f for f in diag.findings if "slip_mm" in f.parameters)
        assert f.location == "sensor:x" and f.parameters["slip_mm"] == pytest.approx(step, rel=0.1)


@pytest.mark.parametrize("effects", [{"creep": {"phi": 0.03, "tau_s": 150.0}},
                                     {"drift": {"rate_x_mm_per_s": 2e-6, "rate_z_mm_per_s": -1.5e-6}}])
def test_a_slow_creep_or_a_drift_is_no_slip(tmp_path, effects):
    """A creep slower than the grid's longest time constant and a drift change a gauge's mean as much as a slip,
    but gradually: no slip is named."""
    model = RigModel(SIM.C_F, effects, noise_mm=0.0006, resolution_mm=0.0001, seed=24)
    path = simulate_recording(model, SCHEDULE, tmp_path / "rec.rig.csv", rod=DESIGN.name)
    for accuracy in ("exact", None):
        diag, _ = diagnose_rig(read_recording(path), SIM, DESIGN, accuracy=accuracy)
        assert not [f for f in diag.findings if "slip_mm" in f.parameters], diag.summary()


def test_a_gauge_stopped_at_both_ends_gets_a_finding_per_end(tmp_path):
    """Loads along y and -y, the y gauge clipped at +-70 % of its largest reading: one finding per end, each with
    its own value."""
    model = RigModel(SIM.C_F, {}, noise_mm=0.0006, resolution_mm=0.001, seed=25)
    path = simulate_recording(model, LoadSchedule(axes=("y", "-y"), repeats=3, hold_s=6.0), tmp_path / "rec.rig.csv",
                              rod=DESIGN.name)
    clipped, stop = _clip_y(path, 0.7)
    diag, _ = diagnose_rig(read_recording(clipped), SIM, DESIGN, accuracy="exact")
    ends = sorted(f.parameters["range_limit_mm"] for f in diag.findings if "range_limit_mm" in f.parameters)
    assert ends == pytest.approx([-stop, stop]), diag.summary()
    assert not _causes(diag), diag.summary()


def test_a_slip_beside_friction_and_creep_on_a_rod_off_its_simulation_is_found(tmp_path):
    """A rod 20 % softer than its simulation, with friction and creep, whose z gauge slips by 12 noise SDs between
    two holds halfway through the z series: the slip is found (fitted beside the rig's own effects) at its size,
    friction at its own; it had been a drift with temperature and friction 18 % off (new-user trial)."""
    model = RigModel(1.2 * SIM.C_F, {"friction": {"F_f_N": 0.3}, "creep": {"phi": 0.015, "tau_s": 6.0}},
                     noise_mm=0.0006, resolution_mm=0.0001, seed=25)
    path = simulate_recording(model, SCHEDULE, tmp_path / "rec.rig.csv", rod=DESIGN.name)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    z_steps = sorted({int(r[1]) for r in rows if r[4] == "z"})
    first, step = z_steps[len(z_steps) // 2], 0.0075
    t0 = min(float(r[0]) for r in rows if int(r[1]) == first)
    diag = _diagnosed_with_slip(path, tmp_path, "z", t0, step, 5)
    f = next((f for f in diag.findings if "slip_mm" in f.parameters), None)
    assert f is not None, diag.summary()
    assert f.location == "sensor:z" and f.parameters["slip_mm"] == pytest.approx(step, rel=0.1), diag.summary()
    fr = next(f for f in diag.findings if f.effect == "friction")
    assert fr.parameters["F_f_N"] == pytest.approx(0.3, rel=0.05), diag.summary()
    assert not [f for f in diag.findings if f.effect == "drift"], diag.summary()


def test_a_slip_within_a_hold_on_a_gauge_reading_to_1_um_is_found(tmp_path):
    """Readings to 1 um with 0.5 um of noise, a rod 1.5x its simulation, the y gauge slipping by 5 um within a hold
    halfway through the y series: the slip is named at its size, no drift beside it. The noise of the residual
    had been the median successive difference, which on 1 um readings is the step itself (1.05 um): the slip read
    4.8 SDs, under the 5 a slip needs, and a drift took its place (a blind tester's rig simulator)."""
    model = RigModel(1.5 * SIM.C_F, {}, noise_mm=0.0005, resolution_mm=0.001, seed=27)
    path = simulate_recording(model, SCHEDULE, tmp_path / "rec.rig.csv", rod=DESIGN.name)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    y_steps = sorted({int(r[1]) for r in rows if r[4] == "y"})
    mid = y_steps[len(y_steps) // 2]
    hold_t = [float(r[0]) for r in rows if int(r[1]) == mid]
    t0, step = 0.5 * (hold_t[0] + hold_t[-1]), 0.005
    diag = _diagnosed_with_slip(path, tmp_path, "y", t0, step, 3)
    f = next((f for f in diag.findings if "slip_mm" in f.parameters), None)
    assert f is not None and f.location == "sensor:y", diag.summary()
    assert f.parameters["slip_mm"] == pytest.approx(step, rel=0.1), diag.summary()
    assert not [f for f in diag.findings if f.effect in ("drift", "creep")], diag.summary()


def _diagnosed_with_slip(path, tmp_path, gauge: str, t0: float, step: float, decimals: int):
    """The diagnosis of ``path`` with the ``gauge`` gauge read ``step`` [mm] high from ``t0`` [s] to the end of its
    own load axis's series."""
    def slip(_, row):
        if row["load_axis"] == gauge and row[f"disp_{gauge}_mm"] and float(row["time_s"]) >= t0:
            row[f"disp_{gauge}_mm"] = f"{float(row[f'disp_{gauge}_mm']) + step:.{decimals}f}"
    slipped = rewrite_recording(path, tmp_path / "slipped.rig.csv", slip)
    return diagnose_rig(read_recording(slipped), SIM, DESIGN)[0]


def test_every_gauge_of_a_series_jumping_at_once_is_the_rod_moving_in_its_clamp(tmp_path):
    """An instrument trial: the rod slipped in its clamp at one hold, 12 um in y and 3 um in z; it had been named a y
    gauge slip, the z step left to a drift and the unexplained. Both gauges stepping at one moment are named together
    (each at its size); one gauge stepping alone stays that gauge's slip."""
    path = _recording(tmp_path, resolution_mm=0.0001)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    y_steps = sorted({int(r[1]) for r in rows if r[4] == "y"})
    t0 = min(float(r[0]) for r in rows if int(r[1]) == y_steps[len(y_steps) // 2])

    def clamp(_, row):
        if row["load_axis"] == "y" and float(row["time_s"]) >= t0:
            row["disp_y_mm"] = f"{float(row['disp_y_mm']) + 0.012:.5f}"
            row["disp_z_mm"] = f"{float(row['disp_z_mm']) + 0.003:.5f}"
    moved = rewrite_recording(path, tmp_path / "clamp.rig.csv", clamp)
    diag = diagnose_rig(read_recording(moved), SIM, DESIGN)[0]
    f = next((f for f in diag.findings if "slip_y_mm" in f.parameters), None)
    assert f is not None and "every gauge of the series jumped" in f.explanation, diag.summary()
    assert f.parameters["slip_y_mm"] == pytest.approx(0.012, rel=0.05)
    assert f.parameters["slip_z_mm"] == pytest.approx(0.003, rel=0.15)
    assert not [g for g in diag.findings if g.effect == "drift"], diag.summary()
    alone = _diagnosed_with_slip(path, tmp_path, "y", t0, 0.012, 5)
    g = next(g for g in alone.findings if "slip" in "".join(g.parameters))
    assert g.location == "sensor:y" and "slip_mm" in g.parameters, alone.summary()
