"""The measured side of the rig fit: per-entry factors r_mn (Eq. 20) and the measured C_F's uncertainty in the
measured compliance file (rodlab.compliance/2), and a load cell's force_N instead of mass x g0."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import calc_rod_compliance, read_compliance, resolve_design, write_compliance
from rodlab.stiffness_rig import fit_recording, read_recording
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

SIM = calc_rod_compliance(resolve_design("rod1"))
QUICK = LoadSchedule(axes=("y", "z", "x"), masses=(0.5, 1.0, 1.5, 2.0), repeats=2, hold_s=4.0, rate_Hz=10.0)


def _record(tmp_path, effects=None, scale=1.0, **model_kw):
    C = SIM.C_F * scale
    model = RigModel(C, effects or {}, seed=3, **model_kw)
    return read_recording(simulate_recording(model, QUICK, tmp_path / "r.rig.csv", rod=SIM.rod)), model


def test_measured_file_stores_r_mn_and_sigma(tmp_path):
    """A rod 8 % more compliant than simulated: every measured entry's r_mn is 1.08, unmeasured ones (load x
    measured y, load y measured x, ...) are null, C_F_sigma is the fit's standard error where measured; the file
    is rodlab.compliance/2 and reads back the same."""
    rec, _ = _record(tmp_path, scale=1.08)
    fit = fit_recording(rec, SIM)
    comp = fit.compliance(SIM, rec)
    sig = np.abs(SIM.C_F) > 1e-6 * np.abs(SIM.C_F).max()
    measured = np.isfinite(fit.C_F_meas)
    np.testing.assert_allclose(comp.r_mn[measured & sig], 1.08, rtol=2e-3)
    assert np.isnan(comp.r_mn[~measured]).all() and np.isnan(comp.r_mn[~sig]).all()
    np.testing.assert_array_equal(np.isfinite(comp.C_F_sigma), measured)
    np.testing.assert_allclose(comp.C_F_sigma[measured], fit.C_F_se[measured])
    back = read_compliance(write_compliance(comp, tmp_path / "m.compliance.json"))
    assert back.format_id == "rodlab.compliance/2"
    np.testing.assert_allclose(back.r_mn, comp.r_mn, rtol=1e-8)
    assert fit.r_rod == pytest.approx(1.08, rel=2e-3)
