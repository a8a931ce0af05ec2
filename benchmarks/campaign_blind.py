"""Score the campaign diagnosis on blind cases: nulls, a wrong fixture pose, a rod compliance off by a factor,
gross alignment errors (outliers), a once-per-revolution joint error, thermal growth, and the pair of a wrong
fixture pose with outliers. The cases come from :mod:`rodlab.calibrate.blind` (the simulator, never diagnosis
code), defined in ``calibrate/blind_cases.toml``.

    python benchmarks/campaign_blind.py [N] [SEED] [pairs|wide|shifts]   # writes docs/benchmarks/campaign_blind[_MODE].md
    CAMPAIGN_BLIND_DEBUG=K python ...                         # the selection's log for case K (0-based)
"""
from __future__ import annotations

import logging
import os
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.diagnose import diagnose_campaign
from rodlab.calibrate import read_campaign, read_fixture, read_points, resolve_robot
from rodlab.calibrate.blind import blind_definitions, generate_campaign_cases
from rodlab.core.fileio import atomic_write_text

def _span(v, unit: str = "", scale: float = 1.0) -> str:
    """``[a, b]`` as ``a-b unit``, a number as itself (the definitions' ranges in a sentence)."""
    a, b = (v if isinstance(v, (list, tuple)) else (v, v))
    text = f"{a * scale:g}" if a == b else f"{a * scale:g}-{b * scale:g}"
    return f"{text} {unit}".strip()


def magnitudes_note() -> list[str]:
    """The injected magnitudes and the wide protocol, read from ``calibrate/blind_cases.toml``."""
    m, w = blind_definitions().magnitudes, blind_definitions().wide
    return [f"Magnitudes (calibrate/blind_cases.toml): fixture offsets N(0, {m['fixture_offset_sd_mm']:g} mm) per "
            f"axis; rod compliance x{'/'.join(f'{k:g}' for k in m['rod_k'])}; {m['outliers']:g} outliers of "
            f"{_span(m['outlier_mm'], 'mm')}; a once-per-revolution error of {_span(m['periodic_amp_deg'], 'deg')} "
            f"on a random joint; arm growth {_span(m['thermal_ppm_per_s'], 'ppm/s')}. `wide` also draws the "
            f"protocol per case ({_span(w['positions'])} clamping positions x {_span(w['orientations'])} "
            f"orientations, device noise {_span(w['device_noise_mm'], 'um', 1e3)}, stated to the diagnosis) and "
            "the misclamped position among all but the world one."]


NOTES = [
    "Detection limit of thermal drift: the growth moves each clamping position by a nearly",
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
    "2026-11-27, the derived rod 1# (40 x 5 mm carbon tubes, c_rod 40 um by the closed form; the legacy rod 1#",
    "of the earlier runs: 832 um): a compliance file off by x1.5 or x0.6 now misplaces the ball by only ~10-20 um",
    "over the campaign, most of which the joint compliances and the kinematic parameters absorb; two such",
    "cases (k = 1.5 in `24 501`, k = 0.6 in `28 601 pairs`) stay `consistent`, at the noise, as the weak thermal",
    "growth does. The validation mean is unchanged in both (the error left is below the device noise).", ""]
OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "campaign_blind.md"


def _run(n: int, seed: int, mode: str) -> list:
    """Generate the cases and diagnose each: [(truth, diagnosis, seconds)]."""
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(resolve_design("rod1"))
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        for i, case in enumerate(generate_campaign_cases(robot, rod, tmp, n, seed, mode)):
            t0 = time.perf_counter()
            logging.getLogger("rodlab").setLevel(logging.DEBUG if str(i) == os.environ.get("CAMPAIGN_BLIND_DEBUG")
                                                 else logging.WARNING)
            folder = case.folder
            diag, _ = diagnose_campaign(robot, read_campaign(folder / "multical.campaign.csv"),
                                        read_fixture(folder / "multical.fixture.json"), rod, noise_mm=case.noise_mm,
                                        validate_points=read_points(folder / "multical.validation.csv"))
            results.append((case.truth, diag, time.perf_counter() - t0))
    return results


def _correct(truth: dict, diag, found: list) -> bool:
    """Null: consistent; effect: named first, a located one at its place; the pair: both named."""
    kind = truth["kind"]
    eff = [f[0] for f in found if f[0] != "unexplained"]
    ok = (kind == "null" and diag.verdict == "consistent") or (kind != "null" and eff and eff[0] == kind)
    if kind in ("fixture_pose", "periodic_joint_error", "thermal_drift"):
        first = [f for f in found if f[0] == kind]
        ok = ok and first[0][1] == truth["location"]
    if kind.startswith("fixture_pose+outlier"):       # a pair: both named, the fixture at its position
        ok = ("fixture_pose", truth["location"]) in found and "outliers" in eff
    if kind == "joint_zero_shift":                    # named first at its position, with its joint
        first = next((f for f in diag.findings if str(f.effect) != "unexplained"), None)
        ok = (first is not None and str(first.effect) == kind and first.location == truth["location"]
              and int(first.parameters.get("joint", 0)) == truth["joint"])
    if kind == "periodic_both":                       # the joint's error with both harmonics
        first = next((f for f in diag.findings if str(f.effect) != "unexplained"), None)
        ok = (first is not None and str(first.effect) == "periodic_joint_error" and first.location == truth["location"]
              and {"amp_sin_rad", "amp2_sin_rad"} <= set(first.parameters))
    return bool(ok)


def _row(truth: dict, diag, dt: float, mode: str, found: list) -> str:
    kind = truth["kind"]
    v = diag.extra.get("validation", {})
    vb, va = v.get("before", {}).get("mean_mm", float("nan")), v.get("after", {}).get("mean_mm", float("nan"))
    desc = {"null": "none", "fixture_pose": truth.get("location"), "rod_deflection": f"k = {truth.get('k')}",
            "outliers": ",".join(truth.get("points", [])),
            "fixture_pose+outliers": f"{truth.get('location')} + {','.join(truth.get('points', []))}",
            "fixture_pose+outlier_inside": f"{truth.get('location')} + {','.join(truth.get('points', []))}",
            "periodic_joint_error": f"{truth.get('location')}, A = {truth.get('amp_deg', 0):.4f} deg",
            "thermal_drift": f"{truth.get('ppm_per_s', 0):.4f} ppm/s",
            "joint_zero_shift": f"{truth.get('location')}, joint {truth.get('joint')}, {truth.get('dtheta_deg', 0):+.4f} deg",
            "periodic_both": f"{truth.get('location')}, A = {truth.get('amp_deg', 0):.4f} + "
                             f"{truth.get('amp2_deg', 0):.4f} deg twice"}[kind]
    if mode == "wide":
        desc += f" ({truth['protocol']})"
    fstr = "; ".join(f"{e} {loc or ''}".strip() for e, loc in found) or "-"
    return f"| {kind} | {desc} | {diag.verdict} | {fstr} | {vb:.3f} -> {va:.3f} | {dt:.1f} |"


def main() -> int:
    logging.basicConfig(format="%(message)s")
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 12
    seed = int(sys.argv[2]) if len(sys.argv) > 2 else 500
    mode = sys.argv[3] if len(sys.argv) > 3 else ""
    kinds = blind_definitions().kinds_of(mode)
    results = _run(n, seed, mode)
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
        s[truth["kind"]] += 1
        s[f"{truth['kind']}_ok"] += _correct(truth, diag, found)
        lines.append(_row(truth, diag, dt, mode, found))
    lines += ["", "Correct (null: consistent; effect: named first, fixture at the right position; the pair: both "
              "named): "
              + ", ".join(f"{k} {s[k + '_ok']}/{s[k]}" for k in kinds if s[k]), ""] + magnitudes_note() + NOTES
    atomic_write_text(OUT.with_name(f"campaign_blind_{mode}.md") if mode else OUT, "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
