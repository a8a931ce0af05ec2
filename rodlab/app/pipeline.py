"""The main job end to end (``rodlab demo``): design -> CAD -> FEA -> rig -> diagnosis -> calibration -> sweep.

Rod 1# of the paper from the built-in design; its CAD (STEP, PNG views) and solid FEA compliance (the frame
model when the CAD extra is absent, said so); a simulated stiffness-rig recording of the same rod with one
concealed effect (a compliant bond at ring 1, the kind of physics the paper suspected in its carbon rods);
the rig fit (r_rod, Fig. 8); the diagnosis and the corrected compliance; a simulated TX90 MultiCal campaign
of the real rod; calibrations with none / calc / fea / meas / corrected compensation (the paper's Table 3,
Fig. 10); an L1 / L2 sweep; a small `rodlab study` of the paper's three carbon rods (predicted
calibration accuracy per method). Everything is written under the run folder with ``run.json`` for the report.
"""
from __future__ import annotations

import json
import logging
import time
from pathlib import Path
from typing import Callable

import numpy as np

from ..compliance import RodCompliance, write_compliance
from ..enums import RigEffect
from ..fileio import atomic_write_json, atomic_write_text, json_safe

__all__ = ["run_demo", "STAGES"]

log = logging.getLogger(__name__)

STAGES = ["design", "cad", "fea", "rig", "fit", "diagnose", "campaign", "calibrate", "sweep", "study"]


def run_demo(out_dir, progress: Callable[[str, str], None] | None = None, seed: int = 7,
             sweep_grid=(np.arange(150, 451, 50.0), np.arange(300, 651, 50.0))) -> dict:
    """Run every stage; returns the summary (also written to ``out_dir/run.json``)."""
    run = _DemoRun(Path(out_dir), seed, sweep_grid)
    run.out.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda stage, msg: log.info("%s: %s", stage, msg))
    timings = {}
    for name in STAGES:
        t0 = time.perf_counter()
        say(name, "started")
        getattr(run, f"stage_{name}")()
        timings[name] = time.perf_counter() - t0
        say(name, f"done in {timings[name]:.1f} s")
    run.summary["timings_s"] = timings
    atomic_write_json(run.out / "run.json", json_safe(run.summary))
    return run.summary


class _DemoRun:
    """The demo's stages (:data:`STAGES`, run in that order), each a method that reads what the earlier ones
    made (attributes set to ``None`` until then) and adds its files and numbers to ``summary``."""

    def __init__(self, out: Path, seed: int, sweep_grid) -> None:
        self.out, self.seed, self.sweep_grid = out, seed, sweep_grid
        self.summary: dict = {"format": "rodlab.run/1", "stages": {}, "files": {}}
        self.design = self.calc = self.fea = self.solid_run = self.C_true = None
        self.rec = self.meas = self.corrected = self.robot = self.calibration = None
        self.cad = False

    def _stage(self, name: str, values: dict) -> None:
        self.summary["stages"][name] = values

    def stage_design(self) -> None:
        from ..calc import calc_rod_compliance
        from ..design_io import resolve_design
        self.design = resolve_design("rod1")
        self.calc = calc_rod_compliance(self.design)
        write_compliance(self.calc, self.out / "rod1.calc.compliance.json")
        self.summary["design"] = self.design.summary()
        self._stage("design", {"mass_kg": self.calc.mass_kg, "c_rod_um_calc": self.calc.c_rod_um})

    def stage_cad(self) -> None:
        from .study.family import cad_available
        self.cad = cad_available()
        if not self.cad:
            self._stage("cad", {"skipped": "the CAD extra (build123d, gmsh) is not installed"})
            return
        import rodlab.geometry as geometry
        c = geometry.build_cad(self.design)
        c.export_step(self.out / "cad" / "rod.step")
        c.write_mass_json(self.out / "cad" / "mass.json")
        views = geometry.render_views(c, self.out / "cad")
        self.summary["files"]["cad_views"] = [str(p.relative_to(self.out)) for p in views]
        self._stage("cad", {"parts": len(c.solids), "mass_kg": c.total_mass_properties().mass_kg})

    def stage_fea(self) -> None:
        if self.cad:
            import rodlab.geometry as geometry
            from rodlab.fea import run_solid
            # one solid run: the compliance, the deformed shape, and the joints that calibrate the sweep's frame
            self.solid_run = run_solid(self.design, geometry.mesh_rod, error_estimate=False, joints=True,
                                       deformed_png=self.out / "fea" / "deformed.png")
            self.fea = self.solid_run.compliance
            self.summary["files"]["fea_deformed"] = "fea/deformed.png"
            model = "solid"
            from .report.views import solid_views
            views = solid_views(self.design, self.solid_run.result, self.out / "fea" / "rod1.vtu")
        else:
            from rodlab.fea import compute_compliance
            self.fea = compute_compliance(self.design, "frame")
            model = "frame (the CAD extra is absent, so no solid FEA)"
            from .report.views import frame_views
            views = frame_views(self.design, self.out / "fea" / "rod1.vtp")
        self.summary["files"]["fea_views"] = [str(p.relative_to(self.out)) for p in views.pngs]
        fea = self.fea
        write_compliance(fea, self.out / "rod1.fea.compliance.json")
        self._stage("fea", {"model": model, "C_F_mm_per_N": fea.C_F.tolist(), "C_g_mm_per_g0": fea.C_g.tolist(),
                            "c_rod_um": fea.c_rod_um,
                            "calc_over_fea_diag": (np.diag(self.calc.C_F) / np.diag(fea.C_F)).tolist(),
                            "fields": str(views.fields.relative_to(self.out)), "views_note": views.note})

    def stage_rig(self) -> None:
        from rodlab.stiffness_rig.effects import joint_places
        from rodlab.stiffness_rig.model import LoadSchedule, RigModel
        from rodlab.stiffness_rig.simulate import simulate_recording
        # a compliant bond at ring 1 [rad/(N m)]
        concealed = {"joint_compliance": {"location": "ring_1", "s_bend_rad_per_Nm": 4.0e-6,
                                          "s_torsion_rad_per_Nm": 1.6e-6}}
        rig_model = RigModel(self.fea.C_F, concealed, noise_mm=0.0006, seed=self.seed,
                             places=joint_places(self.design.tool_mm, self.design))
        self.C_true = rig_model.C_true
        simulate_recording(rig_model, LoadSchedule(), self.out / "rig" / "rod1.rig.csv", rod="1#")
        self._stage("rig", {"concealed_effect": "joint_compliance at ring_1", **{
            k: v for k, v in rig_model.effects[RigEffect.JOINT_COMPLIANCE].items() if k.startswith("s_")}})

    def stage_fit(self) -> None:
        from rodlab.stiffness_rig import fit_recording, plot_fit, read_recording
        self.rec = read_recording(self.out / "rig" / "rod1.rig.csv")
        fit = fit_recording(self.rec, self.fea)
        self.meas = fit.compliance(self.fea, self.rec)
        write_compliance(self.meas, self.out / "rod1.meas.compliance.json")
        plot_fit(fit, self.out / "rig" / "fig8.png", self.fea, title="rod 1#")
        self.summary["files"]["fig8"] = "rig/fig8.png"
        self._stage("fit", {"r_rod": fit.r_rod, "noise_um": fit.noise_mm * 1e3,
                            "C_F_meas_mm_per_N": self.meas.C_F.tolist()})

    def stage_diagnose(self) -> None:
        from .diagnose import corrected_compliance, diagnose_rig
        from .diagnose.plots import plot_rig_diagnosis
        # the demo's recording is simulated from this very FEA file (plus a concealed joint): the simulation is the
        # rod, so it is diagnosed as exact (a rod as built against its design: docs/diagnose.md, `model_form`)
        diag, model = diagnose_rig(self.rec, self.fea, self.design, accuracy="exact")
        diag.write(self.out / "diagnosis.rig.json")
        self.corrected = corrected_compliance(self.fea, diag, model)
        write_compliance(self.corrected, self.out / "rod1.corrected.compliance.json")
        plot_rig_diagnosis(model, self.out / "rig", diag, "1#")
        self.summary["files"]["diagnosis"] = "rig/diagnosis_rig.png"
        values = json.loads(json.dumps(diag.to_dict()))
        values["corrected_vs_true_max_rel"] = float(
            np.max(np.abs(self.corrected.C_F - self.C_true)) / np.max(np.abs(self.C_true)))
        self._stage("diagnose", values)

    def stage_campaign(self) -> None:
        from rodlab.calibrate import resolve_robot
        from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
        fea, C_true = self.fea, self.C_true
        self.robot = resolve_robot("tx90")
        r_true = float((C_true[1, 1] + C_true[2, 2]) / (fea.C_F[1, 1] + fea.C_F[2, 2]))
        rod_true = RodCompliance(fea.rod, fea.method, C_true, r_true * fea.C_g, fea.mass_kg, fea.com_T_mm, fea.tool_mm,
                                 r_true)
        simulate_campaign(self.robot, fea, self.out / "campaign", CampaignSpec(seed=self.seed), rod_true=rod_true)
        self._stage("campaign", {"robot": "tx90", "positions": 5, "orientations": 6, "points": 30,
                                 "r_rod_true": r_true})

    def stage_calibrate(self) -> None:
        from rodlab.calibrate import (ModelParams, Rod, RodDeflection, campaign_observations, identify, read_campaign,
                                      read_fixture, read_points, validate)
        from rodlab.calibrate.plots import plot_error_distributions
        robot, fea, folder = self.robot, self.fea, self.out / "campaign"
        camp = read_campaign(folder / "multical.campaign.csv")
        fix = read_fixture(folder / "multical.fixture.json")
        pts = read_points(folder / "multical.validation.csv")
        nominal_stats, nominal_err, _ = validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)
        table = {"nominal": nominal_stats.to_dict()}
        errors = {"nominal": nominal_err.tolist()}
        for label, rod in (("None", RodCompliance.none_like(fea)), ("Calc", self.calc), ("FEA", fea),
                           ("Meas", self.meas), ("Corrected", self.corrected)):
            res = identify(robot, campaign_observations(camp, fix, rod), Rod.of(fea),
                           [RodDeflection.of(None if label == "None" else rod)])
            st, err, _ = validate(robot, res.params, pts)
            table[label] = dict(st.to_dict(), fit_rms_um=res.rms_mm * 1e3)
            errors[label] = err.tolist()
        plot_error_distributions(errors, self.out / "calibration" / "fig10.png", "MultiCal calibration of a "
                                 "simulated TX90 with rod 1#: validation error per compensation method (the paper's "
                                 "Fig. 10)")
        self.summary["files"]["fig10"] = "calibration/fig10.png"
        self._stage("calibrate", {"table3": table})

    def stage_sweep(self) -> None:
        from rodlab.fea.sweep import run_sweep
        from rodlab.fea.sweep_plot import PAPER_RODS, plot_sweep
        title = "frame model around rod 1#"
        if self.solid_run is not None:                 # that solid run calibrates the frame's joints
            self.calibration = self.solid_run.joints
            title = "frame model joint-calibrated on rod 1#'s solid FEA"
        calibration, folder = self.calibration, self.out / "sweep"
        df = run_sweep(self.design, self.sweep_grid[0], self.sweep_grid[1], model="frame", use_dask=False,
                       cache_dir=folder / "cache", calibration=calibration)
        folder.mkdir(parents=True, exist_ok=True)
        atomic_write_text(folder / "sweep.csv", df.to_csv(index=False))
        plot_sweep(df, folder / "sweep.png", title=title, marks={f"paper {k}": v for k, v in PAPER_RODS.items()})
        ok = df[df["status"] == "ok"]
        best = ok.loc[ok["c_rod_um"].idxmin()]
        self.summary["files"]["sweep"] = "sweep/sweep.png"
        self._stage("sweep", {"designs": int(len(df)), "ok": int(len(ok)), "model": title,
                              "frame_calibration": None if calibration is None else {
                                  "joints_of": calibration.base.name, "margins_mm": list(calibration.margins_mm),
                                  "span_residual": calibration.span_residual},
                              "stiffest": {"L1_mm": float(best["L1_mm"]), "L2_mm": float(best["L2_mm"]),
                                           "c_rod_um": float(best["c_rod_um"])}})

    def stage_study(self) -> None:
        self._stage("study", _study(self.out / "study", self.robot, self.design, self.calibration))
        self.summary["files"]["study_pareto"] = "study/pareto.png"


#: the demo's study: the paper's three carbon rods by the linear predictor (the replicates count only for
#: ``--monte-carlo``)
DEMO_STUDY_RODS, DEMO_STUDY_REPLICATES = ("rod1", "rod2", "rod3"), 5


def _study(out: Path, robot, design, calibration) -> dict:
    """Predicted calibration accuracy of rods 1#-3# on the TX90 (serial; rod 1#'s joint calibration serves the
    family); the study's files in ``out``, its rows for the report."""
    from rodlab.calibrate.simulate import standard_fixture
    from ..design_io import resolve_design
    from .study import StudySpec, list_candidates, run_study, write_study_outputs
    cands = list_candidates([design] + [resolve_design(r) for r in DEMO_STUDY_RODS[1:]])
    spec = StudySpec(replicates=DEMO_STUDY_REPLICATES)
    run = run_study(cands, robot, standard_fixture(), spec, {c.label: calibration for c in cands},
                    out / "cache", use_dask=False)
    note = "frame joint-calibrated on rod 1#'s solid FEA" if calibration is not None else "frame model"
    res = write_study_outputs(out, run, robot.name, False, {"designs": ", ".join(c.label for c in cands),
                                                            "predictor": f"linear ({spec.draws} draws)",
                                                            "compliance": note},
                              designs={c.label: c.design for c in cands})
    cols = ["design", "c_rod_um", "mass_kg", "O1", "method", "mean_mm", "mean_p05_mm", "mean_p95_mm", "max_mm",
            "share_deflection", "share_identification", "share_noise"]
    rows = res.table[res.table["method"].notna()][cols]
    return {"designs": [c.label for c in cands], "replicates": spec.replicates, "compliance": note,
            "predictor": f"linear predictor ({spec.draws} draws of the planned campaign's linear model)",
            "recommendation": res.recommendation.text, "recommended": res.recommendation.to_dict(),
            "r_prior": {st.label: list(st.r_prior) for st in run.setups}, "rows": rows.to_dict(orient="records")}
