"""The study table: one row per design and method (``study.csv``), and the recommendation."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rodlab.calibrate.predict import Priors, summarise
from .prepare import DesignSetup
from .run import StudyRun

__all__ = ["STUDY_COLUMNS", "study_table", "recommend", "Recommendation", "headline_method", "harms", "RECOMMEND_WITHIN"]

STUDY_COLUMNS = ["design", "L1_mm", "L2_mm", "material", "tube", "status", "message", "c_rod_um", "mass_kg",
                 "com_x_mm", "com_z_mm", "reach_mm", "O1", "O2", "O3", "O4", "O5", "method", "mean_mm", "max_mm",
                 "median_mm", "mean_p05_mm", "mean_p95_mm", "rms_mm", "share_deflection", "share_identification",
                 "share_noise", "share_slip", "slip_scatter_um", "nominal_mean_mm", "r_rod_low", "r_rod_high",
                 "replicates", "failed",
                 "thermal_um_per_K", "thermal_x_um_per_K", "thermal_z_um_per_K", "f1_Hz", "f2_Hz", "f3_Hz",
                 "tube_stress_MPa", "tube_margin", "bond_stress_MPa", "bond_margin", "compliance_model"]


def _design_part(s: DesignSetup) -> dict:
    row = {"design": s.label, "L1_mm": s.L1_mm, "L2_mm": s.L2_mm, "material": s.material, "tube": s.tube,
           "status": str(s.status), "message": s.message, "compliance_model": s.compliance_model,
           "r_rod_low": s.r_prior[0], "r_rod_high": s.r_prior[1]}
    if s.fea is not None:
        row.update(c_rod_um=s.fea.c_rod_um, mass_kg=s.fea.mass_kg, com_x_mm=float(s.fea.com_T_mm[0]),
                   com_z_mm=float(s.fea.com_T_mm[2]), reach_mm=float(np.linalg.norm(s.fea.tool_mm)))
        th = np.asarray(s.thermal_um_per_K, float)
        row.update(thermal_um_per_K=float(np.linalg.norm(th)), thermal_x_um_per_K=float(th[0]),
                   thermal_z_um_per_K=float(th[2]))
        row.update({f"f{i + 1}_Hz": float(v) for i, v in enumerate(s.frequencies_Hz)})
        row.update({k: s.strength.get(k) for k in ("tube_stress_MPa", "tube_margin", "bond_stress_MPa",
                                                  "bond_margin")})
    row.update({k: s.observability.get(k, math.nan) for k in ("O1", "O2", "O3", "O4", "O5")})
    return row


def _slip_scatter_um(s: DesignSetup, slip: float) -> float:
    """The scatter the rod's slip adds to each reading of a campaign [um, rms per coordinate]: ``slip C_g u`` with
    ``u ~ N(0, I/3)`` has ``E|.|^2 = slip^2 tr(C_g C_g^T) / 3`` over three coordinates (the simulated rod's C_g)."""
    if s.fea is None or not slip:
        return 0.0 if s.fea is not None else math.nan
    Cg = np.asarray(s.fea.C_g, float)
    return float(1e3 * slip * np.sqrt(np.trace(Cg @ Cg.T) / 9.0))


def study_table(run: StudyRun):
    """A pandas DataFrame with :data:`STUDY_COLUMNS`: a row per design and method (one row, without a method,
    for a design that is invalid, unreachable or failed)."""
    import pandas as pd

    rows = []
    slip = run.spec.priors.rod_slip if run.spec.priors is not None else Priors().rod_slip   # None: the defaults
    preds = run.predictions or [None] * len(run.setups)
    for s, outs, pred in zip(run.setups, run.outcomes, preds):
        base = dict(_design_part(s), slip_scatter_um=_slip_scatter_um(s, slip))
        if pred is not None:
            nominal, summaries = pred.nominal_mean_mm, pred.summaries
        elif not s.ok or not outs:
            rows.append(dict(base, message=s.message or "no replicate succeeded"))
            continue
        else:
            nominal, summaries = float(np.mean([o.before.mean_mm for o in outs])), summarise(outs, run.spec.methods)
        for a in summaries:
            b = a.budget
            rows.append(dict(base, method=str(a.method), mean_mm=a.mean_mm, max_mm=a.max_mm, median_mm=a.median_mm,
                             mean_p05_mm=a.mean_p05_mm, mean_p95_mm=a.mean_p95_mm, rms_mm=a.rms_mm,
                             share_deflection=b.deflection, share_identification=b.identification,
                             share_noise=b.noise, share_slip=b.slip, nominal_mean_mm=nominal, replicates=a.replicates,
                             failed=a.failed))
    df = pd.DataFrame(rows)
    for c in STUDY_COLUMNS:
        if c not in df:
            df[c] = np.nan
    return df[STUDY_COLUMNS]


def headline_method(df) -> str:
    """The method a study's recommendation is for: the best compensation studied (Meas, else FEA, Calc, None)."""
    for m in ("meas", "fea", "calc", "none"):
        if (df["method"] == m).any():
            return m
    return str(df["method"].dropna().iloc[0])


def harms(rows):
    """Which rows (one design and method each) leave the robot less accurate than its nominal model (a boolean
    Series; False where the nominal is not known)."""
    return rows["mean_mm"] >= rows["nominal_mean_mm"]


@dataclass(frozen=True)
class Recommendation:
    """The design to build: its label and lengths [mm], the method its prediction is for, and the sentence."""

    design: str | None
    L1_mm: float
    L2_mm: float
    method: str | None
    text: str

    def to_dict(self) -> dict:
        return {"design": self.design, "L1_mm": self.L1_mm, "L2_mm": self.L2_mm, "method": self.method,
                "text": self.text}


#: a design whose predicted mean error is within this share of the best one's is as good for the recommendation,
#: which then takes the lightest of them
RECOMMEND_WITHIN = 0.10


def recommend(df) -> Recommendation:
    """The design to build and why. Among the designs whose predicted mean (with the best method studied:
    Meas, else FEA, ...) lies within :data:`RECOMMEND_WITHIN` of the best one's, the lightest; designs that would
    leave the robot less accurate than its nominal model are left out while any other is usable (and said). (The
    rule had been "within the best one's 90 % band": every design is predicted on the same draws, so that band,
    one campaign's luck, is no measure of the designs' difference; a designer trial's aluminium rod 46 % worse
    than the carbon one had been recommended for being lighter.)"""
    ok = df[(df["status"] == "ok") & df["method"].notna()]
    if ok.empty:
        reasons = "; ".join(sorted({f"{r.design}: {r.message}" for r in df.itertuples()})[:3])
        return Recommendation(None, math.nan, math.nan, None, f"no design is usable on this robot ({reasons})")
    m = headline_method(ok)
    rows = ok[ok["method"] == m]
    helps = rows[~harms(rows)]                                      # better than uncalibrated (or no nominal)
    pool = helps if len(helps) else rows
    best = pool.loc[pool["mean_mm"].idxmin()]
    close = pool[pool["mean_mm"] <= (1.0 + RECOMMEND_WITHIN) * best["mean_mm"]]
    # the lightest, and among designs as light (a rod and its as-built design) the most accurate
    pick = close.loc[close.sort_values(["mass_kg", "mean_mm"]).index[0]]
    why = (f"predicted mean error {pick['mean_mm']:.3f} mm with {m} compensation (90 % band "
           f"{pick['mean_p05_mm']:.3f}-{pick['mean_p95_mm']:.3f} mm), c_rod {pick['c_rod_um']:.0f} um, mass "
           f"{pick['mass_kg']:.3f} kg")
    if pick["design"] == best["design"]:
        text = (f"build {pick['design']}: the most accurate of {len(pool)} designs; {why}" if len(pool) > 1 else
                f"build {pick['design']}: the only design studied that can be recommended; {why}")
    else:
        text = (f"build {pick['design']}: the lightest of the {len(close)} designs within "
                f"{100 * RECOMMEND_WITHIN:.0f} % of the best one's predicted mean error (best {best['design']}, "
                f"{best['mean_mm']:.3f} mm); {why}")
    return Recommendation(str(pick["design"]), float(pick["L1_mm"]), float(pick["L2_mm"]), m,
                          text + _harm_note(rows, helps, pick))


def _harm_note(rows, helps, pick) -> str:
    """What the recommendation must add when designs leave the robot less accurate than uncalibrated."""
    if not len(helps):
        return (f"; but no design improves on the robot's nominal model ({pick['nominal_mean_mm']:.3f} mm "
                "uncalibrated): calibrating with any of them would do harm (see the warnings)")
    if len(helps) < len(rows):
        return (f" ({len(rows) - len(helps)} of {len(rows)} designs, left out, would leave the robot less accurate "
                "than uncalibrated)")
    return ""
