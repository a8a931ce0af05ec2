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


def _causes(diag) -> list:
    return [f for f in diag.findings if f.effect not in ("unexplained", "model_form")]


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_a_gauge_at_its_stop_is_unexplained_at_the_gauge_and_left_out(tmp_path, accuracy):
    """The y gauge clipped at 70 % of its largest reading (the largest load alone reaches it, noise-free there):
    its readings at the stop are left out and named; nothing else is found."""
    path = _recording(tmp_path)
    rows = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
    stop = round(0.7 * max(abs(float(r[7])) for r in rows if r[7]), 4)

    def clip(_, row):
        if row["disp_y_mm"] and abs(float(row["disp_y_mm"])) > stop:
            row["disp_y_mm"] = f"{stop if float(row['disp_y_mm']) > 0 else -stop:.4f}"
    clipped = rewrite_recording(path, tmp_path / "clipped.rig.csv", clip)
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
