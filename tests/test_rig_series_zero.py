"""The gauges are zeroed at every series' start, so a recording that loads an axis both ways (x and -x series)
has a zero per gauge and series: a zero that differs between the two series is a nuisance, not physics (it had
been read as crosstalk and a tare when the zeros of x and -x were one)."""
from __future__ import annotations

import numpy as np
import pytest

from conftest import legacy_design, rewrite_recording
from rodlab import calc_rod_compliance
from rodlab.app.diagnose import diagnose_rig
from rodlab.core.enums import Verdict
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.samples import rig_samples
from rodlab.stiffness_rig.simulate import simulate_recording

DESIGN = legacy_design("rod1")
SIM = calc_rod_compliance(DESIGN)
BOTH_WAYS = LoadSchedule(axes=("y", "-y", "z", "-z"), masses=(0.5, 1.0, 1.5), repeats=3, hold_s=6.0)


def _rezeroed(tmp_path, offset_mm: float, schedule=BOTH_WAYS, shifted=lambda row, seen: row["load_axis"][0] == "-"):
    """A recording whose gauges were zeroed ``offset_mm`` lower for the series ``shifted`` picks (by default the
    -y and -z series: one noisy zero reading each, or a gauge reset between the series); ``seen`` the load axes of
    the series before the row's."""
    model = RigModel(SIM.C_F, {}, noise_mm=0.0006, resolution_mm=0.001, seed=5)
    path = simulate_recording(model, schedule, tmp_path / "rec.rig.csv", rod=DESIGN.name)
    runs = []

    def shift(_, row):
        if not runs or runs[-1] != row["load_axis"]:
            runs.append(row["load_axis"])
        if shifted(row, runs[:-1]):
            for c in ("disp_x_mm", "disp_y_mm", "disp_z_mm"):
                if row[c]:
                    row[c] = f"{float(row[c]) + offset_mm:.4f}"
    return read_recording(rewrite_recording(path, tmp_path / "rezeroed.rig.csv", shift))


def test_each_series_has_its_own_gauge_zeros(tmp_path):
    data = rig_samples(_rezeroed(tmp_path, 0.0))
    assert np.unique(data.series).size == 4
    for series in np.unique(data.series):
        axis, sign = np.unique(data.axis[data.series == series]), np.unique(data.sign[data.series == series])
        assert axis.size == 1 and sign.size == 1                   # one load axis and sign per series
    # a gauge of the y and -y series: two zero groups
    y_gauge = (data.comp == 1) & (data.axis == 1)
    assert np.unique(data.zero_groups[y_gauge]).size == 2


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_a_zero_that_differs_between_x_and_minus_x_is_not_physics(tmp_path, accuracy):
    """2 um (3 noise SDs) between the zeros of a gauge's two series: consistent on either path, no cause."""
    diag, _ = diagnose_rig(_rezeroed(tmp_path, 0.002), SIM, DESIGN, accuracy=accuracy)
    assert diag.verdict is Verdict.CONSISTENT, [f.effect for f in diag.findings]


@pytest.mark.parametrize("accuracy", ["exact", None])
def test_an_axis_loaded_again_later_is_a_series_of_its_own(tmp_path, accuracy):
    """y, z, then y again: the gauges are zeroed at each of the three series; 2 um between the two y series'
    zeros is a nuisance, not a drift."""
    yzy = LoadSchedule(axes=("y", "z", "y"), masses=(0.5, 1.0, 1.5), repeats=3, hold_s=6.0)
    rec = _rezeroed(tmp_path, 0.002, yzy, lambda row, seen: row["load_axis"] in seen)
    data = rig_samples(rec)
    assert np.unique(data.series).size == 3
    diag, _ = diagnose_rig(rec, SIM, DESIGN, accuracy=accuracy)
    assert diag.verdict is Verdict.CONSISTENT, [f.effect for f in diag.findings]
