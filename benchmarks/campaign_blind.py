"""Blind cases for the campaign diagnosis: nulls, a wrong fixture pose, a rod compliance off by a factor,
gross alignment errors (outliers), a once-per-revolution joint error, thermal growth, and the pair of a wrong
fixture pose with outliers; generated with
``calibrate.simulate`` (never diagnosis code).

    python benchmarks/campaign_blind.py [N] [SEED] [pairs|wide]   # writes docs/benchmarks/campaign_blind[_MODE].md
    CAMPAIGN_BLIND_DEBUG=K python ...                         # the selection's log for case K (0-based)
"""
from __future__ import annotations

import csv
import logging
import os
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
    "each accepted term; both models are cross-validated on the same points (outliers left out).",
    "An outlier inside the badly clamped position itself (`wide`: fixture_pose+outlier_inside) was answered",
    "`unexplained`: the least-squares fit smeared both errors over every residual (median Birge ratio ~15, which",
    "also inflated the fixture-pose uncertainty so that a 0.2 mm offset read as 1.3 sigma), the point with the",
    "largest least-squares residual was an innocent neighbour, and a Cholesky whitening folded a position's",
    "first point into its later rows. Fixed (2026-11-24): the scale comes from a robust (Tukey biweight) fit,",
    "the outlier candidate is the largest robust residual, the whitening is the covariance's symmetric square",
    "root, and a significant candidate that fails cross-validation gives way to the next. On the project's",
    "own generator of that pair (40 seeds): 30/40 both named before, 39/40 after (the miss is a 0.03 mm offset).",
    "The null of `28 601 pairs` that is `unexplained` is the noise itself: the simulated device noise of that",
    "draw has a standard deviation 1.32 times the stated 3 um over its 90 readings (p = 1.6e-5); across 240",
    "other null seeds the residual test's p-values are uniform (p < 0.05 in 15/240, none below 1e-3). Diagnose",
    "now says the excess is spread evenly over the positions (a device noisier than stated, 4.0 um) and",
    "`rodlab calibrate` trusts the result with a caution (Birge ratio 1.34 <= 1.5).",
    "`wide` also draws the protocol per case (4-6 clamping positions x 5-8 orientations, device noise 2-5 um,",
    "stated to the diagnosis) and the misclamped position among all but the world one.", ""]
KINDS = ["null", "fixture_pose", "rod_deflection", "outliers", "periodic_joint_error", "thermal_drift"]
PAIRS = ["fixture_pose+outliers"]
WIDE = PAIRS + ["fixture_pose+outlier_inside"]      # `wide`: also an outlier inside the misclamped position
OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "campaign_blind.md"


def _outliers(path: Path, rng, k: int, inside: int | None = None):
    """Add ``k`` gross alignment errors to random points (with ``inside``: the first at that position)."""
    rows = list(csv.reader(path.read_text().splitlines()))
    if inside is None:
        idx = rng.choice(np.arange(1, len(rows)), size=k, replace=False)
    else:
        at = [i for i in range(1, len(rows)) if rows[i][0] == str(inside)]
        rest = [i for i in range(1, len(rows)) if rows[i][0] != str(inside)]
        idx = [int(rng.choice(at))] + [int(i) for i in rng.choice(rest, size=k - 1, replace=False)]
    labels = []
    for i in idx:
        for c in (-5, -4, -3):
            rows[i][c] = f"{float(rows[i][c]) + rng.choice([-1, 1]) * rng.uniform(0.15, 0.4):.4f}"
        labels.append(f"{rows[i][0]}.{rows[i][1]}")
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    return labels


def main() -> int:
    logging.basicConfig(format="%(message)s")
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    mode = sys.argv[3] if len(sys.argv) > 3 else ""
    kinds = KINDS + {"pairs": PAIRS, "wide": WIDE}.get(mode, [])
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
            protocol = {}
            if mode == "wide":                            # other protocols and device noise, stated to diagnose
                protocol = {"positions": int(rng.integers(4, 7)), "orientations": int(rng.integers(5, 9)),
                            "device_noise_mm": round(float(rng.uniform(0.002, 0.005)), 4)}
            npos = protocol.get("positions", 5)
            if kind.startswith("fixture_pose"):           # any position but the world one (1 + npos // 2)
                j = int(rng.choice([p for p in range(1, npos + 1) if p != 1 + npos // 2]))
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
            spec = CampaignSpec(seed=int(rng.integers(1 << 30)), **protocol)
            truth["protocol"] = f"{spec.positions}x{spec.orientations}, {spec.device_noise_mm * 1e3:.1f} um"
            simulate_campaign(robot, rod, out, spec, effects=effects)
            if kind.endswith("outliers"):
                truth["points"] = _outliers(out / "multical.campaign.csv", rng, 2)
            if kind.endswith("outlier_inside"):                # one of the two inside the misclamped position
                truth["points"] = _outliers(out / "multical.campaign.csv", rng, 2,
                                            int(truth["location"].split(":")[1]))
            t0 = time.perf_counter()
            logging.getLogger("rodlab").setLevel(logging.DEBUG if str(i) == os.environ.get("CAMPAIGN_BLIND_DEBUG")
                                                 else logging.WARNING)
            diag, _ = diagnose_campaign(robot, read_campaign(out / "multical.campaign.csv"),
                                        read_fixture(out / "multical.fixture.json"), rod, noise_mm=spec.device_noise_mm,
                                        validate_points=read_points(out / "multical.validation.csv"))
            results.append((truth, diag, time.perf_counter() - t0))
    s = Counter()
    lines = ["# Blind benchmark: campaign diagnosis", "",
             f"`python benchmarks/campaign_blind.py {n} {seed}{' ' + mode if mode else ''}`: simulated TX90 campaigns "
             "with rod 1# ("
             + ("4-6 positions x 5-8 orientations, 2-5 um device noise (per case, in brackets)" if mode == "wide"
                else "5 x 6 points, 3 um device noise")
             + f", fixture poses measured to 0.01 mm / 0.002 deg), {time.strftime('%Y-%m-%d')}.", "",
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
        if kind.startswith("fixture_pose+outlier"):       # a pair: both named, the fixture at its position
            ok = ("fixture_pose", truth["location"]) in found and "outliers" in eff
        s[f"{kind}_ok"] += bool(ok)
        v = diag.extra.get("validation", {})
        vb, va = v.get("before", {}).get("mean_mm", float("nan")), v.get("after", {}).get("mean_mm", float("nan"))
        desc = {"null": "none", "fixture_pose": truth.get("location"), "rod_deflection": f"k = {truth.get('k')}",
                "outliers": ",".join(truth.get("points", [])),
                "fixture_pose+outliers": f"{truth.get('location')} + {','.join(truth.get('points', []))}",
                "fixture_pose+outlier_inside": f"{truth.get('location')} + {','.join(truth.get('points', []))}",
                "periodic_joint_error": f"{truth.get('location')}, A = {truth.get('amp_deg', 0):.4f} deg",
                "thermal_drift": f"{truth.get('ppm_per_s', 0):.4f} ppm/s"}[kind]
        if mode == "wide":
            desc += f" ({truth['protocol']})"
        fstr = "; ".join(f"{e} {loc or ''}".strip() for e, loc in found) or "-"
        lines.append(f"| {kind} | {desc} | {diag.verdict} | {fstr} | {vb:.3f} -> {va:.3f} | {dt:.1f} |")
    lines += ["", "Correct (null: consistent; effect: named first, fixture at the right position; the pair: both "
              "named): "
              + ", ".join(f"{k} {s[k + '_ok']}/{s[k]}" for k in kinds if s[k]), ""] + NOTES
    atomic_write_text(OUT.with_name(f"campaign_blind_{mode}.md") if mode else OUT, "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
