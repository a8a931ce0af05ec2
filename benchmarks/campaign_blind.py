"""Blind cases for the campaign diagnosis: nulls, a wrong fixture pose, a rod compliance off by a factor,
gross alignment errors (outliers), a once-per-revolution joint error, thermal growth, and the pair of a wrong
fixture pose with outliers; generated with
``calibrate.simulate`` (never diagnosis code).

    python benchmarks/campaign_blind.py [N] [SEED] [pairs]   # writes docs/benchmarks/campaign_blind[_pairs].md
"""
from __future__ import annotations

import csv
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

import numpy as np

from rodlab.calibrate import read_campaign, read_fixture, read_points, resolve_robot
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.diagnose import diagnose_campaign
from rodlab.fileio import atomic_write_text

NOTES = [
    "Magnitudes: fixture offsets N(0, 0.12 mm) per axis; rod compliance x0.6/1.5/2.0; two 0.15-0.4 mm outliers; a",
    "once-per-revolution error of 0.002-0.008 deg on a random joint; arm growth 0.01-0.05 ppm/s (0.3-2 K over the",
    "campaign for steel). Detection limit of thermal drift: the growth moves each clamping position by a nearly",
    "constant offset that the kinematic parameters absorb; only its change within a position (~0.4 ppm per 500 s",
    "position at 0.013 ppm/s, ~3 um) is evidence, so growth below ~0.02 ppm/s stays `consistent` — correctly at",
    "the noise. A periodic joint error is carried into the re-identification as a joint-angle correction",
    "q + a_s sin q + a_c cos q (applied to the validation points too, as a controller would); an error of a joint",
    "whose range is small (J2, J3) is partly absorbed by its offset, so its amplitude reads low.",
    "A null campaign once drew false alarms (thermal_drift, rod_deflection, periodic_joint_error on 5 of 8",
    "nulls): the first hypothesis was credited with what the generalised-least-squares refit of the identified",
    "parameters gains over the unweighted identification. Fixed: the baseline is that refit.",
    "The pair (a wrong fixture pose with two outliers, `pairs`) was answered `unexplained` naming neither: each",
    "outlier point used up one of the three model terms, the Birge ratio (13x) estimated with the gross errors in",
    "the residuals hid the fixture pose, and leave-one-point-out cross-validation predicted the dropped outliers.",
    "Fixed: outliers are points, not terms (up to a tenth of the points); the Birge ratio is re-estimated after",
    "each accepted term; both models are cross-validated on the same points (outliers left out). Still hard: an",
    "outlier inside the badly clamped position itself (answered `unexplained` at that position).",
    "Open: one null of `28 601 pairs` is `unexplained` (reduced chi-square 1.78 over 58 dof, p = 2e-4; the same",
    "before the pair fix): a false alarm the residual test raises on this draw, cause not yet found.", ""]
KINDS = ["null", "fixture_pose", "rod_deflection", "outliers", "periodic_joint_error", "thermal_drift"]
PAIRS = ["fixture_pose+outliers"]
OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "campaign_blind.md"


def _outliers(path: Path, rng, k: int):
    rows = list(csv.reader(path.read_text().splitlines()))
    idx = rng.choice(np.arange(1, len(rows)), size=k, replace=False)
    labels = []
    for i in idx:
        for c in (-5, -4, -3):
            rows[i][c] = f"{float(rows[i][c]) + rng.choice([-1, 1]) * rng.uniform(0.15, 0.4):.4f}"
        labels.append(f"{rows[i][0]}.{rows[i][1]}")
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    return labels


def main() -> int:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    pairs = len(sys.argv) > 3 and sys.argv[3] == "pairs"
    kinds = KINDS + PAIRS if pairs else KINDS
    rng = np.random.default_rng(seed)
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(resolve_design("rod1"))
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(n):
            kind = kinds[i % len(kinds)]
            out = Path(tmp) / f"c{i}"
            truth = {"kind": kind, "effect": None if kind == "null" else kind}
            effects = []                                  # (name, parameters) of the campaign effect registry
            if kind.startswith("fixture_pose"):
                j = int(rng.choice([1, 2, 4, 5]))
                effects.append(("fixture_pose", {"position": j, "offset_mm": list(rng.normal(0, 0.12, 3))}))
                truth["location"] = f"position:{j}"
            if kind == "rod_deflection":
                k = float(rng.choice([0.6, 1.5, 2.0]))
                effects.append(("rod_deflection", {"k": k}))
                truth["k"] = k
            if kind == "periodic_joint_error":
                k = int(rng.integers(1, 7))
                amp, phase = float(rng.choice([-1, 1]) * rng.uniform(0.002, 0.008)), float(rng.uniform(0, 360))
                effects.append(("periodic_joint_error", {"joint": k, "amp_deg": amp, "phase_deg": phase}))
                truth["location"] = f"joint:{k}"
                truth["amp_deg"] = amp
            if kind == "thermal_drift":
                therm = float(rng.uniform(0.01, 0.05))
                effects.append(("thermal_drift", {"growth_ppm_per_s": therm}))
                truth["location"] = "time"
                truth["ppm_per_s"] = therm
            simulate_campaign(robot, rod, out, CampaignSpec(seed=int(rng.integers(1 << 30))), effects=effects)
            if kind.endswith("outliers"):
                truth["points"] = _outliers(out / "multical.campaign.csv", rng, 2)
            t0 = time.perf_counter()
            diag, _ = diagnose_campaign(robot, read_campaign(out / "multical.campaign.csv"),
                                        read_fixture(out / "multical.fixture.json"), rod,
                                        validate_points=read_points(out / "multical.validation.csv"))
            results.append((truth, diag, time.perf_counter() - t0))
    s = Counter()
    lines = ["# Blind benchmark: campaign diagnosis", "",
             f"`python benchmarks/campaign_blind.py {n} {seed}{' pairs' if pairs else ''}`: simulated TX90 campaigns "
             "with rod 1# (5 x 6 points, "
             f"3 um device noise, fixture poses measured to 0.01 mm / 0.002 deg), {time.strftime('%Y-%m-%d')}.", "",
             "| case | truth | verdict | findings | validation mean before -> after [mm] | s |", "|---|---|---|---|---|---|"]
    for truth, diag, dt in results:
        found = [(f.effect, f.location) for f in diag.findings]
        eff = [f[0] for f in found if f[0] != "unexplained"]
        kind = truth["kind"]
        s[kind] += 1
        ok = (kind == "null" and diag.verdict == "consistent") or (kind != "null" and eff and eff[0] == kind)
        if kind in ("fixture_pose", "periodic_joint_error", "thermal_drift"):
            first = [f for f in found if f[0] == kind]
            ok = ok and first[0][1] == truth["location"]
        if kind == "fixture_pose+outliers":               # a pair: both named, the fixture at its position
            ok = ("fixture_pose", truth["location"]) in found and "outliers" in eff
        s[f"{kind}_ok"] += bool(ok)
        v = diag.extra.get("validation", {})
        vb, va = v.get("before", {}).get("mean_mm", float("nan")), v.get("after", {}).get("mean_mm", float("nan"))
        desc = {"null": "none", "fixture_pose": truth.get("location"), "rod_deflection": f"k = {truth.get('k')}",
                "outliers": ",".join(truth.get("points", [])),
                "fixture_pose+outliers": f"{truth.get('location')} + {','.join(truth.get('points', []))}",
                "periodic_joint_error": f"{truth.get('location')}, A = {truth.get('amp_deg', 0):.4f} deg",
                "thermal_drift": f"{truth.get('ppm_per_s', 0):.4f} ppm/s"}[kind]
        fstr = "; ".join(f"{e} {loc or ''}".strip() for e, loc in found) or "-"
        lines.append(f"| {kind} | {desc} | {diag.verdict} | {fstr} | {vb:.3f} -> {va:.3f} | {dt:.1f} |")
    lines += ["", "Correct (null: consistent; effect: named first, fixture at the right position; the pair: both "
              "named): "
              + ", ".join(f"{k} {s[k + '_ok']}/{s[k]}" for k in kinds if s[k]), ""] + NOTES
    atomic_write_text(OUT.with_name("campaign_blind_pairs.md") if pairs else OUT, "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
