"""The library tour (docs/examples/library_tour.py) runs as docs/library.md shows it, and its numbers are physics:
the frame model within 15 % of the closed form's c_rod, the calibration far below the nominal robot's error, a
simulated campaign with nothing left out diagnosed consistent. Also: library entry points given a name where an
object is expected, or numbers in the CLI's units, say so up front."""
from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np
import pytest

import rodlab
from rodlab import calibrate as cal

TOUR = Path(__file__).resolve().parents[1] / "docs" / "examples" / "library_tour.py"


def _tour():
    spec = importlib.util.spec_from_file_location("library_tour", TOUR)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module                  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_the_library_tour_runs_and_its_numbers_are_physics(tmp_path):
    t = _tour().run(tmp_path)
    assert 30.0 < t.c_rod_calc_um < 60.0 and abs(t.c_rod_frame_um / t.c_rod_calc_um - 1.0) < 0.15
    assert t.calibrated_mean_mm < 0.1 * t.nominal_mean_mm and t.trusted
    assert t.verdict == "consistent" and t.recommended in ("1#", "2#", "3#")


def test_library_entry_points_say_what_they_expected():
    design = rodlab.resolve_design("rod1")
    with pytest.raises(TypeError, match="resolve_design"):
        rodlab.calc_compliance("rod1")
    with pytest.raises(TypeError, match="resolve_robot"):
        cal.simulate_campaign("tx90", rodlab.calc_rod_compliance(design), "unused")
    with pytest.raises(TypeError, match="calc_rod_compliance"):
        cal.Rod.of(design)
    with pytest.raises(cal.CalibrationError, match="the noise is in mm"):
        cal.CampaignSpec(device_noise_mm=3)
    with pytest.raises(cal.CalibrationError, match="whole number"):
        cal.CampaignSpec(positions="5")
    CF, Cg = rodlab.calc_compliance(design)
    with pytest.raises(rodlab.ComplianceError, match="3 x 3"):
        rodlab.c_rod_um(CF[:2], Cg)
    with pytest.raises(rodlab.ComplianceError, match="force_N"):
        rodlab.c_rod_um(CF, Cg, force_N=-1)
    assert rodlab.c_rod_um(CF, Cg, force_N=np.array([1.10, 1.25, 1.05])) == pytest.approx(rodlab.c_rod_um(CF, Cg))
    with pytest.raises(rodlab.ComplianceError, match="measured c22"):
        rodlab.r_rod(np.zeros((3, 3)), CF)
