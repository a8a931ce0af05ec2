"""The main job end to end (``rodlab demo``): design -> CAD -> FEA -> rig -> diagnosis -> calibration -> sweep.

Rod 1# of the paper from the built-in design; its CAD (STEP, PNG views) and solid FEA compliance (the frame
model when the CAD extra is absent, said so); a simulated stiffness-rig recording of the rod as built, which is
not its simulation (the laminate 7 % softer, inside its tolerance, and a starved bond at ring 1, the kind of
physics the paper suspected in its carbon rods) on a rig with friction; the rig fit (r_rod, Fig. 8); the
diagnosis against the design's FEA within its tolerances, the corrected compliance and the rod as built
(``rodlab update``: the laminate and the located bond, ``rod1.asbuilt.rod.toml``); a simulated TX90 MultiCal campaign
of the real rod; calibrations with none / calc / fea / meas / corrected compensation (the paper's Table 3,
Fig. 10); an L1 / L2 sweep; a small `rodlab study` of the paper's three carbon rods (predicted
calibration accuracy per method). Everything is written under the run folder with ``run.json`` for the report.
"""
from __future__ import annotations

import json
import logging
import time
from contextlib import ExitStack
from pathlib import Path
from typing import Callable

import numpy as np

from rodlab.calibrate import (
    ModelParams,
    Rod,
    RodDeflection,
    campaign_observations,
    identify,
    read_campaign,
    read_fixture,
    read_points,
    resolve_robot,
    validate,
)
from rodlab.calibrate.plots import plot_error_distributions
from rodlab.calibrate.predict import Priors
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign, standard_fixture
from rodlab.core.design_edit import write_edited_design
from rodlab.core.sensitivity import with_values
from rodlab.fea import compute_compliance, run_solid
from rodlab.fea.frame import frame_compliance
from rodlab.fea.sweep import run_sweep
from rodlab.fea.sweep_plot import PAPER_RODS, plot_sweep
from rodlab.stiffness_rig import fit_recording, plot_fit, read_recording
from rodlab.stiffness_rig.effects import joint_places
from rodlab.stiffness_rig.model import LoadSchedule, RigModel
from rodlab.stiffness_rig.simulate import simulate_recording

from ..core.blas_threads import one_blas_thread
from ..core.calc import calc_rod_compliance
from ..core.compliance import RodCompliance, write_compliance
from ..core.design_io import resolve_design
from ..core.figures_bg import background_figures
from ..core.fileio import atomic_write_json, atomic_write_text, json_safe
from ..core.units import PAPER_ROD_SLIP
from ..core.view3d import start_offscreen_check
from .demo_cad import CadJob, start_cad_job
from .diagnose import corrected_compliance, diagnose_rig
from .diagnose.plots import plot_rig_diagnosis
from .report.views import frame_views, solid_views
from .solid_mesher import solid_mesher
from .study import StudySpec, list_candidates, run_study, write_study_outputs
from .study.family import cad_available
from .update import Measured, update_design

__all__ = ["run_demo", "STAGES"]

log = logging.getLogger(__name__)

#: the demo's rod (built-in)
DEMO_ROD = "rod1"

STAGES = ["design", "fea", "cad", "rig", "fit", "diagnose", "campaign", "calibrate", "sweep", "study"]


def run_demo(out_dir, progress: Callable[[str, str], None] | None = None, seed: int = 7,
             sweep_grid=(np.arange(150, 451, 50.0), np.arange(300, 651, 50.0))) -> dict:
    """Run every stage; returns the summary (also written to ``out_dir/run.json``)."""
    run = _DemoRun(Path(out_dir), seed, sweep_grid)
    run.out.mkdir(parents=True, exist_ok=True)
    say = progress or (lambda stage, msg: log.info("%s: %s", stage, msg))
    timings = {}
    start_offscreen_check()                      # the 3-D views' probe (~2 s) runs beside the solid FEA
    with background_figures():                   # every figure rendered in a second process; all written here
        try:
            _run_stages(run, say, timings)
        finally:                                 # a stage failed or Ctrl-C: the CAD child stopped first
            if run.cad_job is not None:
                run.cad_job.cancel()
    run.summary["stages"] = {name: run.summary["stages"][name] for name in STAGES}
    run.summary["timings_s"] = {name: timings[name] for name in STAGES}
    atomic_write_json(run.out / "run.json", json_safe(run.summary))
    return run.summary


def _run_stages(run: _DemoRun, say, timings: dict) -> None:
    """Every stage in :data:`STAGES` order; the CAD stage, started in a second process, finished last. The
    stages from the CAD stage on run with one OpenBLAS thread (:func:`~rodlab.core.blas_threads.one_blas_thread`):
    the CAD and figure processes run beside them."""
    with ExitStack() as beside:
        for name in STAGES:
            if name == "cad":
                beside.enter_context(one_blas_thread())
            t0 = time.perf_counter()
            say(name, "started" if name != "cad" or not run.cad else
                "started in a second process, beside the stages after it")
            getattr(run, f"stage_{name}")()
            if name != "cad" or run.cad_job is None:
                timings[name] = time.perf_counter() - t0
                say(name, f"done in {timings[name]:.1f} s")
    if run.cad_job is not None:
        timings["cad"] = run.finish_cad()
        say("cad", f"done in {timings['cad']:.1f} s (beside the other stages)")


class _DemoRun:
    """The demo's stages (:data:`STAGES`, run in that order), each a method that reads what the earlier ones
    made (attributes set to ``None`` until then) and adds its files and numbers to ``summary``."""

    def __init__(self, out: Path, seed: int, sweep_grid) -> None:
        self.out, self.seed, self.sweep_grid = out, seed, sweep_grid
        self.summary: dict = {"format": "rodlab.run/1", "stages": {}, "files": {}}
        self.design = self.calc = self.fea = self.solid_run = self.C_true = self.Cg_true = None
        self.rec = self.meas = self.corrected = self.robot = self.calibration = None
        self.cad = cad_available()           # the CAD extra: CAD views and the solid FEA
        self.cad_job: CadJob | None = None

    def _stage(self, name: str, values: dict) -> None:
        self.summary["stages"][name] = values

    def stage_design(self) -> None:
        self.design = resolve_design(DEMO_ROD)
        self.calc = calc_rod_compliance(self.design)
        write_compliance(self.calc, self.out / "rod1.calc.compliance.json")
        self.summary["design"] = self.design.summary()
        self._stage("design", {"mass_kg": self.calc.mass_kg, "c_rod_um_calc": self.calc.c_rod_um})

    def stage_cad(self) -> None:
        """Start the CAD stage in a second process (:mod:`.demo_cad`; nothing later reads it); see
        :meth:`finish_cad`."""
        if not self.cad:
            self._stage("cad", {"skipped": "the CAD extra (build123d, gmsh) is not installed"})
            return
        self.cad_job = start_cad_job(DEMO_ROD, self.out / "cad")

    def finish_cad(self) -> float:
        """Wait for the CAD stage; its files and numbers into the summary; its wall time [s]."""
        made = self.cad_job.result()
        self.summary["files"]["cad_views"] = [str(p.relative_to(self.out)) for p in made.views]
        self._stage("cad", {"parts": made.parts, "mass_kg": made.mass_kg})
        return made.seconds

    def stage_fea(self) -> None:
        if self.cad:
            # one solid run: the compliance, the deformed shape, and the joints that calibrate the sweep's frame
            self.solid_run = run_solid(self.design, solid_mesher(self.design), error_estimate=False, joints=True,
                                       deformed_png=self.out / "fea" / "deformed.png")
            self.fea = self.solid_run.compliance
            self.summary["files"]["fea_deformed"] = "fea/deformed.png"
            model = "solid"
            views = solid_views(self.design, self.solid_run.result, self.out / "fea" / "rod1.vtu")
        else:
            self.fea = compute_compliance(self.design, "frame")
            model = "frame (the CAD extra is absent, so no solid FEA)"
            views = frame_views(self.design, self.out / "fea" / "rod1.vtp")
        self.summary["files"]["fea_views"] = [str(p.relative_to(self.out)) for p in views.pngs]
        fea = self.fea
        write_compliance(fea, self.out / "rod1.fea.compliance.json")
        self._stage("fea", {"model": model, "C_F_mm_per_N": fea.C_F.tolist(), "C_g_mm_per_g0": fea.C_g.tolist(),
                            "c_rod_um": fea.c_rod_um,
                            "calc_over_fea_diag": (np.diag(self.calc.C_F) / np.diag(fea.C_F)).tolist(),
                            "fields": str(views.fields.relative_to(self.out)), "views_note": views.note})

    def stage_rig(self) -> None:
        C_F, C_g, as_built = self._rod_as_built()
        rig_effects = {"friction": {"F_f_N": 0.1}}          # the rig's own: its slides
        rig_model = RigModel(C_F, rig_effects, noise_mm=0.0006, seed=self.seed,
                             places=joint_places(self.design.tool_mm, self.design))
        self.C_true, self.Cg_true = rig_model.C_true, C_g
        simulate_recording(rig_model, LoadSchedule(), self.out / "rig" / "rod1.rig.csv", rod="1#")
        self._stage("rig", {"concealed_effect": "the rod as built: laminate E -7 % (inside its 15 % tolerance) and a "
                            "starved ring-1 bond (s_bend 2e-5 rad/(N m), 20x a sound bond's tolerance); the rig's "
                            "slides with 0.1 N of friction", "as_built": as_built, "rig_effects": rig_effects})

    def _rod_as_built(self) -> tuple[np.ndarray, np.ndarray, dict]:
        """(C_F, C_g, the drawn keys) of the rod as built: the design's FEA plus the frame model's change for a
        laminate 7 % softer than designed and a compliant ring-1 bond (the demo's rod is not its simulation)."""
        m = self.design.pipe_I.material
        as_built = {f"materials.{m.name}.E_GPa": round(0.93 * m.E_GPa, 3), "joints.ring_1.s_bend_rad_per_Nm": 2.0e-5}
        built, nominal = frame_compliance(with_values(self.design, as_built)), frame_compliance(self.design)
        return self.fea.C_F + built[0] - nominal[0], self.fea.C_g + built[1] - nominal[1], as_built

    def stage_fit(self) -> None:
        self.rec = read_recording(self.out / "rig" / "rod1.rig.csv")
        fit = fit_recording(self.rec, self.fea)
        self.meas = fit.compliance(self.fea, self.rec)
        write_compliance(self.meas, self.out / "rod1.meas.compliance.json")
        plot_fit(fit, self.out / "rig" / "fig8.png", self.fea, title="rod 1#")
        self.summary["files"]["fig8"] = "rig/fig8.png"
        self._stage("fit", {"r_rod": fit.r_rod, "noise_um": fit.noise_mm * 1e3,
                            "C_F_meas_mm_per_N": self.meas.C_F.tolist()})

    def stage_diagnose(self) -> None:
        # the rod as built is not its simulation: the default diagnosis judges the linear part against the design's
        # tolerances and the FEA's accuracy, and names only what lies beyond them (docs/diagnose.md)
        diag, model = diagnose_rig(self.rec, self.fea, self.design)
        diag.write(self.out / "diagnosis.rig.json")
        self.corrected = corrected_compliance(self.fea, diag, model, self.rec.loaded_axes(), design=self.design)
        write_compliance(self.corrected, self.out / "rod1.corrected.compliance.json")
        plot_rig_diagnosis(model, self.out / "rig", diag, "1#")
        self.summary["files"]["diagnosis"] = "rig/diagnosis_rig.png"
        values = json.loads(json.dumps(diag.to_dict()))
        values["corrected_vs_true_max_rel"] = float(
            np.max(np.abs(self.corrected.C_F - self.C_true)) / np.max(np.abs(self.C_true)))
        values["update"] = self._update(diag, model)
        self._stage("diagnose", values)

    def _update(self, diag, model) -> dict:
        """`rodlab update` on the diagnosed linear part: the laminate's E and G and each located joint's compliance,
        written as the rod as built (``rod1.asbuilt.rod.toml``, the design file with the fitted values)."""
        m = self.design.pipe_I.material
        keys = [f"materials.{m.name}.E_GPa"] + ([f"materials.{m.name}.G_GPa"] if m.G_GPa is not None else [])
        keys += [f"joints.{f.location.split('|')[0]}.s_bend_rad_per_Nm" for f in diag.findings
                 if f.effect == "joint_compliance" and f.location]
        lin = model.linear
        res = update_design(self.design, Measured(lin.entries, lin.C, lin.cov, "rig/rod1.rig.csv"), keys)
        write_edited_design(Path(self.design.source).read_text(encoding="utf-8"), self.design,
                            dict(zip(res.keys, res.x)), self.out / "rod1.asbuilt.rod.toml",
                            "# as built: rodlab update rod1 --measured rig/rod1.rig.csv --free " + ",".join(keys)
                            + " --model frame\n")
        return {"file": "rod1.asbuilt.rod.toml", "keys": list(res.keys), "design": res.nominal.tolist(),
                "as_built": res.x.tolist(), "sigma": res.sigma.tolist(), "r_before": res.r_before.tolist(),
                "r_after": res.r_after.tolist(), "inseparable": [a for a, *_ in res.inseparable]}

    def stage_campaign(self) -> None:
        fea, C_true = self.fea, self.C_true
        self.robot = resolve_robot("tx90")
        r_true = float((C_true[1, 1] + C_true[2, 2]) / (fea.C_F[1, 1] + fea.C_F[2, 2]))
        rod_true = RodCompliance(fea.rod, fea.method, C_true, self.Cg_true, fea.mass_kg, fea.com_T_mm, fea.tool_mm,
                                 r_true)
        simulate_campaign(self.robot, fea, self.out / "campaign", CampaignSpec(seed=self.seed), rod_true=rod_true)
        self._stage("campaign", {"robot": "tx90", "positions": 5, "orientations": 6, "points": 30,
                                 "r_rod_true": r_true})

    def stage_calibrate(self) -> None:
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
        self.summary["files"]["study_views"] = [str(p.relative_to(self.out))      # where pyvista rendered them
                                                for p in sorted((self.out / "study").glob("recommended.3d_*.png"))]


#: the demo's study: the paper's three carbon rods by the linear predictor (the replicates count only for
#: ``--monte-carlo``)
DEMO_STUDY_RODS, DEMO_STUDY_REPLICATES = ("rod1", "rod2", "rod3"), 5


def _study(out: Path, robot, design, calibration) -> dict:
    """Predicted calibration accuracy of rods 1#-3# on the TX90 (serial; rod 1#'s joint calibration serves the
    family); the study's files in ``out``, its rows for the report."""
    cands = list_candidates([design] + [resolve_design(r) for r in DEMO_STUDY_RODS[1:]])
    spec = StudySpec(replicates=DEMO_STUDY_REPLICATES, priors=Priors(rod_slip=PAPER_ROD_SLIP))
    run = run_study(cands, robot, standard_fixture(), spec, {c.label: calibration for c in cands},
                    out / "cache", use_dask=False)
    note = "frame joint-calibrated on rod 1#'s solid FEA" if calibration is not None else "frame model"
    res = write_study_outputs(out, run, robot.name, False, {"designs": ", ".join(c.label for c in cands),
                                                            "predictor": f"linear ({spec.draws} draws)",
                                                            "compliance": note},
                              designs={c.label: c.design for c in cands})
    cols = ["design", "c_rod_um", "mass_kg", "O1", "method", "mean_mm", "mean_p05_mm", "mean_p95_mm", "max_mm",
            "share_deflection", "share_slip", "share_identification", "share_noise"]
    rows = res.table[res.table["method"].notna()][cols]
    return {"designs": [c.label for c in cands], "replicates": spec.replicates, "compliance": note,
            "predictor": f"linear predictor ({spec.draws} draws of the planned campaign's linear model)",
            "recommendation": res.recommendation.text, "recommended": res.recommendation.to_dict(),
            "r_prior": {st.label: list(st.r_prior) for st in run.setups}, "rows": rows.to_dict(orient="records")}
