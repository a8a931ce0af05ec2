"""rodlab as a library: a rod design to a calibrated robot, in one script (docs/library.md walks through it).

    python docs/examples/library_tour.py [OUT_DIR]

:func:`run` returns the numbers it prints, as a :class:`Tour`; ``tests/test_library_tour.py`` runs it and checks them.
Units: lengths in mm, angles in the files and results in degrees; :class:`rodlab.calibrate.ModelParams` holds its
angles in radians (it is the model's internal state, not a file's).
"""
from __future__ import annotations

import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

import rodlab
from rodlab import calibrate as cal
from rodlab import fea


@dataclass(frozen=True)
class Tour:
    """What the tour found: c_rod [um] of the closed form and the frame model; the validation mean error [mm] of the
    nominal robot and of the calibrated one; the diagnosis's verdict; the study's recommended design."""

    c_rod_calc_um: float
    c_rod_frame_um: float
    nominal_mean_mm: float
    calibrated_mean_mm: float
    trusted: bool
    verdict: str
    recommended: str


def compliance(design) -> tuple:
    """The rod's compliance two ways: the closed form (paper Eqs. 15-18) and the frame model."""
    calc = rodlab.calc_rod_compliance(design)                  # a RodCompliance: C_F [mm/N], C_g [mm/g0] in {T}
    frame = fea.compute_compliance(design, "frame")
    return calc, frame


def calibrate_simulated(robot, rod, out: Path):
    """A simulated MultiCal campaign of ``robot`` with ``rod`` (files in ``out``), calibrated and validated."""
    cal.simulate_campaign(robot, rod, out, cal.CampaignSpec(seed=7))    # campaign, fixture, validation, truth files
    camp = cal.read_campaign(out / "multical.campaign.csv")
    fix = cal.read_fixture(out / "multical.fixture.json")
    pts = cal.read_points(out / "multical.validation.csv")
    obs = cal.campaign_observations(camp, fix, rod)
    res = cal.identify(robot, obs, cal.Rod.of(rod), [cal.RodDeflection.of(rod)], cal.FitOptions())
    before, _, _ = cal.validate(robot, cal.ModelParams.nominal(robot, pts.tool_mm), pts)
    after, _, _ = cal.validate(robot, res.params, pts)
    return res, before, after, (camp, fix)


def diagnose(robot, camp, fix, rod) -> str:
    """The campaign diagnosis's verdict (``consistent`` for a simulated campaign with nothing left out)."""
    from rodlab.app.diagnose import diagnose_campaign
    report, _ = diagnose_campaign(robot, camp, fix, rod)
    return str(report.verdict)


def study(robot) -> str:
    """The linear predictor's recommendation among rods 1#-3# (the paper's carbon rods)."""
    from rodlab.app.study import StudySpec, list_candidates, recommend, run_study, study_table
    cands = list_candidates([rodlab.resolve_design(r) for r in ("rod1", "rod2", "rod3")])
    run = run_study(cands, robot, cal.standard_fixture(), StudySpec(methods=("none", "calc")), use_dask=False)
    return str(recommend(study_table(run)).design)


def run(out_dir) -> Tour:
    out = Path(out_dir)
    design = rodlab.resolve_design("rod1")                   # a built-in, or a *.rod.toml
    calc, frame = compliance(design)
    robot = cal.resolve_robot("tx90")
    res, before, after, (camp, fix) = calibrate_simulated(robot, calc, out)
    return Tour(calc.c_rod_um, frame.c_rod_um, before.mean_mm, after.mean_mm, not res.warnings,
                diagnose(robot, camp, fix, calc), study(robot))


if __name__ == "__main__":
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="rodlab-tour-"))
    print(run(folder))
