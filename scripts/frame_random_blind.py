"""Blind test of the frame model on random designs inside its calibrated range, and of family calibration.

    python scripts/frame_random_blind.py --solve 101 202   # draw 30 designs per seed, solve them (~4 min each)
    python scripts/frame_random_blind.py --families [NAME ...]   # two L1 / L2 variants of each (default: the
                                                                 # 10 worst under the global calibration; ~3 min)
    python scripts/frame_random_blind.py --joints          # solve each family base with the tip moments and
                                                           # store its section motions (joint calibration; ~1 min)
    python scripts/frame_random_blind.py                   # report from fea/data/solid_random_reference.json

Each design draws its tube material, diameter and r_m / t, its bend material, wall, h = t R / r_m^2 and angle,
rings (or none) and the pipe holder at random, and is kept only if the frame model calls it inside its
calibrated range (:func:`fea.frame.frame_range_notes` is empty). None of them was used to fit anything. The
solid references are stored so that ``tests/test_frame_vs_solid.py`` checks the figures in docs/fea.md; for
each family base also the joint calibration's measurements (:mod:`fea.joints`: the rigid motions of its four
sections and of the tip under nine load cases), so that the test re-derives the calibration without a solid run.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rodlab.fea.reference_designs import family_errors, spec_design as design
from rodlab.fea.reference_designs import random_global_errors as global_errors
from rodlab.core.fileio import atomic_write_json

REF = Path(__file__).resolve().parents[1] / "fea" / "data" / "solid_random_reference.json"
#: families drawn only to test the joint calibration blind (its margin was fixed before they were drawn)
JOINT_BLIND = REF.with_name("solid_joint_blind_reference.json")
N_PER_SEED = 30
N_FAMILIES = 10
#: the two L1 / L2 variants of a family base [mm] (v0: shorter L1, longer L2; v1: the opposite)
VARIANTS = ((-80.0, 100.0), (70.0, -90.0))


def random_spec(rng) -> dict:
    """One random design (contract rod-design fields)."""
    tm = str(rng.choice(["cfrp", "cfrp_rolled", "steel_304", "al_7075", "al_6061", "ti_6al4v"]))
    od = round(rng.uniform(16, 30) * 2) / 2
    t = round(od / (2 * rng.uniform(4.2, 10.0) + 1), 1)          # tube r_m / t 4.2-10
    bm = str(rng.choice(["steel_304", "steel_304", "al_7075", "ti_6al4v"]) if tm.startswith("cfrp")
             else rng.choice([tm, "steel_304", "ti_6al4v"]))
    tb = round(od / (2 * rng.uniform(4.2, 7.6) + 1), 1)         # bend r_m / t 4.2-7.6
    r_m = (od - tb) / 2
    R = round(rng.uniform(0.45, 1.0) * r_m ** 2 / tb)            # h 0.45-1.0
    spec = {"L1_mm": float(round(rng.uniform(200, 450))), "L2_mm": float(round(rng.uniform(300, 600))),
            "gamma_deg": float(round(rng.uniform(60, 150))),
            "tube": {"material": tm, "outer_diameter_mm": od, "wall_mm": t},
            "bend": {"material": bm, "radius_mm": float(R), "wall_mm": tb}}
    if rng.uniform() < 0.8:
        spec["rings"] = {"material": str(rng.choice(["al_7075", "steel_304", "ti_6al4v"])),
                         "outer_diameter_mm": od + round(rng.uniform(2, 5) * 2),
                         "length_mm": float(round(rng.uniform(25, 60)))}
    else:
        spec["rings"] = {"length_mm": 0.0}
    spec["pipe_holder"] = {"material": str(rng.choice(["al_7075", "steel_304", "ti_6al4v"])),
                           "outer_diameter_mm": od + round(rng.uniform(8, 16)),
                           "length_mm": float(round(rng.uniform(30, 50)))}
    return spec


def random_specs(seed: int, n: int = N_PER_SEED, in_range: bool = True) -> dict:
    """``n`` valid random designs of ``seed``, named ``rnd{seed}_{i:02d}``; with ``in_range`` only those inside the
    global frame calibration's range."""
    from rodlab.fea.frame import frame_range_notes
    rng = np.random.default_rng(seed)
    out = {}
    while len(out) < n:
        name, spec = f"rnd{seed}_{len(out):02d}", random_spec(rng)
        try:
            d = design(name, spec)
        except Exception:           # an invalid draw (parts too long for L1, ...): draw again
            continue
        if not in_range or not frame_range_notes(d):
            out[name] = spec
    return out


def variant_specs(base: str, spec: dict) -> dict:
    """The family variants of ``base``: the same parts at other L1 / L2 (L1 lengthened if too short)."""
    out = {}
    for k, (d1, d2) in enumerate(VARIANTS):
        v = json.loads(json.dumps(spec))
        v["L1_mm"], v["L2_mm"] = max(150.0, spec["L1_mm"] + d1), max(250.0, spec["L2_mm"] + d2)
        try:
            design("x", v)
        except Exception:
            v["L1_mm"] = spec["L1_mm"] + 60.0
        out[f"{base}_v{k}"] = v
    return out


def solve(specs: dict, refs: dict, path: Path = REF) -> None:
    from rodlab.fea import solid_compliance
    from rodlab.geometry import mesh_rod
    for name, spec in specs.items():
        if name in refs["designs"]:
            continue
        comp, res = solid_compliance(design(name, spec), mesh_rod, error_estimate=False)
        refs["designs"][name] = {"spec": spec, "C_F": comp.C_F.tolist(), "C_g": comp.C_g.tolist(), "dofs": res.dofs}
        atomic_write_json(path, refs)
        print(name, res.dofs, flush=True)


def solve_joints(refs: dict, path: Path = REF) -> None:
    """Solve each family base with the tip moments and store its joint calibration's measurements."""
    from rodlab.fea import solid_compliance
    from rodlab.fea.joints import measure_sections
    from rodlab.geometry import mesh_rod
    refs.setdefault("joints", {})
    for base in refs["families"]:
        if base in refs["joints"]:
            continue
        d = design(base, refs["designs"][base]["spec"])
        _, res = solid_compliance(d, mesh_rod,
                                  error_estimate=False, keep_displacements=True, tip_moments=True)
        sec, tip, margins = measure_sections(d, res)
        refs["joints"][base] = {"section_motion": sec.tolist(), "tip_motion": tip.tolist(),
                                "margins_mm": list(margins.values())}
        atomic_write_json(path, refs)
        print(base, "joints stored", flush=True)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--solve", type=int, nargs="*", help="seeds whose random designs to solve")
    ap.add_argument("--families", nargs="*", default=None, help="bases whose variants to solve (default: worst 10)")
    ap.add_argument("--joints", action="store_true", help="solve the family bases for the joint calibration")
    ap.add_argument("--joint-blind", type=int, nargs=2, metavar=("SEED", "N"),
                    help="draw N new random families of SEED to test the joint calibration blind")
    args = ap.parse_args()
    if args.joint_blind:
        seed, n = args.joint_blind
        blind = json.loads(JOINT_BLIND.read_text()) if JOINT_BLIND.exists() else {"designs": {}, "families": []}
        specs = random_specs(seed, n, in_range=False)
        solve(specs, blind, JOINT_BLIND)
        for base, spec in specs.items():
            solve(variant_specs(base, spec), blind, JOINT_BLIND)
        blind["families"] = sorted(set(blind["families"]) | set(specs))
        solve_joints(blind, JOINT_BLIND)
    refs = json.loads(REF.read_text()) if REF.exists() else {"designs": {}, "families": []}
    for seed in args.solve or []:
        solve(random_specs(seed), refs)
    if args.families is not None:
        worst = sorted(global_errors(refs).items(), key=lambda kv: -kv[1])[:N_FAMILIES]
        refs["families"] = sorted(args.families or [n for n, _ in worst])
        for base in refs["families"]:
            solve(variant_specs(base, refs["designs"][base]["spec"]), refs)
        atomic_write_json(REF, refs)
    if args.joints:
        solve_joints(refs)
    g = global_errors(refs)
    m = np.array(list(g.values()))
    print(f"global calibration on {m.size} random designs: max {100 * m.max():.2f} %, median of the per-design "
          f"max {100 * np.median(m):.2f} %, > 1 %: {int(np.sum(m > 0.01))}, > 2 %: {int(np.sum(m > 0.02))}")
    for label, data in (("", refs), (" (joint blind)", json.loads(JOINT_BLIND.read_text())
                                       if JOINT_BLIND.exists() else {})):
        for base, e in family_errors(data).items():
            print(f"  family {base}{label}: variants {100 * e['global']:.2f} % global, {100 * e['joints']:.2f} % "
                  f"joint-calibrated on one solid run of the base")
    return 0


if __name__ == "__main__":
    sys.exit(main())
