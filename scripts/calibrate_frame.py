"""Calibrate the frame model's constants against the solid model, and validate them.

    python scripts/calibrate_frame.py --solve   # (re)compute the solid references (~15 min, needs cad extra)
    python scripts/calibrate_frame.py --solve-missing   # only the references not stored yet
    python scripts/calibrate_frame.py           # fit on the calibration set and the part probes, report the rest

The solid references (graded curved-P2 mesh at the default size) are stored in
``fea/data/solid_reference.json`` so that tests can compare the frame model with them cheaply.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rodlab.design_io import design_from_dict, resolve_design
from rodlab.fileio import atomic_write_json

sys.path.insert(0, str(Path(__file__).resolve().parent))
from frame_probes import PROBES, THIN_PROBES  # noqa: E402

REF = Path(__file__).resolve().parents[1] / "fea" / "data" / "solid_reference.json"

OFF_GRID = {
    "A": {"L1_mm": 220.0, "L2_mm": 480.0, "gamma_deg": 110.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 22.0, "wall_mm": 1.5},
          "bend": {"material": "steel_304", "radius_mm": 40.0},
          "rings": {"outer_diameter_mm": 28.0, "length_mm": 40.0}},
    "B": {"L1_mm": 350.0, "L2_mm": 380.0, "gamma_deg": 75.0,
          "tube": {"material": "steel_304", "outer_diameter_mm": 18.0, "wall_mm": 1.5}, "bend": {"radius_mm": 30.0}},
    "C": {"L1_mm": 250.0, "L2_mm": 550.0, "gamma_deg": 135.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 25.0, "wall_mm": 2.0},
          "bend": {"material": "al_7075", "radius_mm": 45.0}},
    "D": {"L1_mm": 200.0, "L2_mm": 500.0, "gamma_deg": 180.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 20.0, "wall_mm": 2.0}},
    "E": {"L1_mm": 400.0, "L2_mm": 300.0, "gamma_deg": 90.0,
          "tube": {"material": "al_7075", "outer_diameter_mm": 25.0, "wall_mm": 2.5},
          "bend": {"radius_mm": 50.0}, "rings": {"material": "steel_304"}},
    # added 2026-11-23: thin titanium / steel / aluminium walls, UD and rolled carbon with steel bends, other
    # angles, rings and holders. F-J fitted; K-O held out (L's error led to the von Karman bend factor);
    # P-T blind: solved and compared once, after the model and its constants were frozen
    "F": {"L1_mm": 280.0, "L2_mm": 420.0, "gamma_deg": 100.0,
          "tube": {"material": "ti_6al4v", "outer_diameter_mm": 22.0, "wall_mm": 1.5},
          "bend": {"radius_mm": 35.0}},
    "G": {"L1_mm": 320.0, "L2_mm": 350.0, "gamma_deg": 120.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 25.0, "wall_mm": 2.0},
          "bend": {"material": "steel_304", "radius_mm": 50.0}, "rings": {"length_mm": 30.0}},
    "H": {"L1_mm": 180.0, "L2_mm": 600.0, "gamma_deg": 80.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 20.0, "wall_mm": 1.5},
          "bend": {"material": "steel_304", "radius_mm": 30.0},
          "pipe_holder": {"material": "steel_304", "outer_diameter_mm": 40.0}},
    "I": {"L1_mm": 450.0, "L2_mm": 250.0, "gamma_deg": 150.0,
          "tube": {"material": "al_6061", "outer_diameter_mm": 30.0, "wall_mm": 3.0},
          "bend": {"radius_mm": 60.0}},
    "J": {"L1_mm": 250.0, "L2_mm": 400.0, "gamma_deg": 90.0,
          "tube": {"material": "steel_304", "outer_diameter_mm": 16.0, "wall_mm": 1.0},
          "bend": {"radius_mm": 25.0}},
    "K": {"L1_mm": 260.0, "L2_mm": 520.0, "gamma_deg": 95.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 28.0, "wall_mm": 2.0},
          "bend": {"material": "ti_6al4v", "radius_mm": 45.0}, "rings": {"material": "ti_6al4v", "length_mm": 45.0}},
    "L": {"L1_mm": 380.0, "L2_mm": 300.0, "gamma_deg": 65.0,
          "tube": {"material": "steel_304", "outer_diameter_mm": 22.0, "wall_mm": 2.5},
          "bend": {"radius_mm": 45.0}, "rings": {"material": "al_7075"}},
    "M": {"L1_mm": 230.0, "L2_mm": 450.0, "gamma_deg": 125.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 22.0, "wall_mm": 2.0},
          "bend": {"material": "al_7075", "radius_mm": 40.0}, "rings": {"material": "al_7075", "length_mm": 35.0}},
    "N": {"L1_mm": 300.0, "L2_mm": 380.0, "gamma_deg": 90.0,
          "tube": {"material": "al_6061", "outer_diameter_mm": 20.0, "wall_mm": 1.5},
          "bend": {"radius_mm": 32.0}},
    "O": {"L1_mm": 420.0, "L2_mm": 450.0, "gamma_deg": 110.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 25.0, "wall_mm": 2.5},
          "bend": {"material": "steel_304", "radius_mm": 40.0}, "rings": {"material": "steel_304", "length_mm": 40.0}},
    "P": {"L1_mm": 340.0, "L2_mm": 560.0, "gamma_deg": 100.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 30.0, "wall_mm": 2.0},
          "bend": {"material": "al_7075", "radius_mm": 55.0}, "rings": {"length_mm": 50.0}},
    "Q": {"L1_mm": 200.0, "L2_mm": 350.0, "gamma_deg": 70.0,
          "tube": {"material": "ti_6al4v", "outer_diameter_mm": 18.0, "wall_mm": 1.2},
          "bend": {"radius_mm": 30.0}, "rings": {"material": "ti_6al4v", "length_mm": 30.0}},
    "R": {"L1_mm": 450.0, "L2_mm": 400.0, "gamma_deg": 140.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 25.0, "wall_mm": 1.5},
          "bend": {"material": "steel_304", "radius_mm": 45.0}, "rings": {"material": "al_7075", "length_mm": 60.0}},
    "S": {"L1_mm": 280.0, "L2_mm": 480.0, "gamma_deg": 90.0,
          "tube": {"material": "al_7075", "outer_diameter_mm": 25.0, "wall_mm": 1.5},
          "bend": {"radius_mm": 40.0}, "rings": {"material": "al_7075"}},
    "T": {"L1_mm": 320.0, "L2_mm": 420.0, "gamma_deg": 110.0,
          "tube": {"material": "steel_304", "outer_diameter_mm": 20.0, "wall_mm": 2.0},
          "bend": {"radius_mm": 35.0}, "rings": {"material": "steel_304", "length_mm": 25.0},
          "pipe_holder": {"material": "steel_304", "outer_diameter_mm": 34.0, "length_mm": 50.0}},
    # blind, second round (2026-11-23): designed, solved and compared once after frame revision 3 (part probes,
    # saturating bend restraint, holder correction) was frozen; no ring (U, Z), steel rings (V), steel / Ti
    # holders (W, X), a 1 mm titanium wall (Y)
    "U": {"L1_mm": 300.0, "L2_mm": 450.0, "gamma_deg": 95.0,
          "tube": {"material": "steel_304", "outer_diameter_mm": 20.0, "wall_mm": 1.5},
          "bend": {"radius_mm": 35.0}, "rings": {"length_mm": 0.0}},
    "V": {"L1_mm": 260.0, "L2_mm": 520.0, "gamma_deg": 115.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 24.0, "wall_mm": 1.8},
          "bend": {"material": "steel_304", "radius_mm": 42.0},
          "rings": {"material": "steel_304", "outer_diameter_mm": 32.0, "length_mm": 50.0}},
    "W": {"L1_mm": 380.0, "L2_mm": 360.0, "gamma_deg": 80.0,
          "tube": {"material": "al_7075", "outer_diameter_mm": 22.0, "wall_mm": 2.0},
          "bend": {"radius_mm": 38.0}, "pipe_holder": {"material": "steel_304", "outer_diameter_mm": 36.0}},
    "X": {"L1_mm": 220.0, "L2_mm": 600.0, "gamma_deg": 100.0,
          "tube": {"material": "cfrp_rolled", "outer_diameter_mm": 22.0, "wall_mm": 1.5},
          "bend": {"material": "ti_6al4v", "radius_mm": 36.0}, "rings": {"material": "ti_6al4v", "length_mm": 35.0},
          "pipe_holder": {"material": "ti_6al4v", "outer_diameter_mm": 34.0, "length_mm": 45.0}},
    "Y": {"L1_mm": 330.0, "L2_mm": 400.0, "gamma_deg": 130.0,
          "tube": {"material": "ti_6al4v", "outer_diameter_mm": 20.0, "wall_mm": 1.0},
          "bend": {"radius_mm": 32.0}, "rings": {"length_mm": 36.0}},
    "Z": {"L1_mm": 280.0, "L2_mm": 380.0, "gamma_deg": 90.0,
          "tube": {"material": "cfrp", "outer_diameter_mm": 22.0, "wall_mm": 2.0},
          "bend": {"material": "steel_304", "radius_mm": 40.0, "wall_mm": 2.0}, "rings": {"length_mm": 0.0}},
}
CALIBRATION_SET = ["rod1", "rod2", "rod3", "rod4", "rod5", "rod6", "A", "B", "C", "D", "E", "F", "G", "H", "I", "J",
                   "rod1_L1_200_L2_600", "rod4_L1_420_L2_330"]
VALIDATION_SET = ["K", "L", "M", "N", "O", "P", "Q", "R", "S", "T", "U", "V", "W", "X", "Y", "Z"]
#: part probes (one joint each; scripts/frame_probes.py), fitted with the calibration set
PROBE_SET = list(PROBES)
#: thin-walled bends outside the calibrated range (not fitted; reported, and flagged by the frame)
THIN_SET = list(THIN_PROBES)
#: off-grid members of the paper's two families (same sections, other L1 / L2): per-family calibration
FAMILY_OFF_GRID = {"rod1_L1_200_L2_600": ("rod1", 200.0, 600.0), "rod4_L1_420_L2_330": ("rod4", 420.0, 330.0),
                   "Y_L1_260_L2_480": ("Y", 260.0, 480.0)}
#: Y (1 mm titanium bend) lies outside the global calibration's range: its family shows what --calibrate recovers
FAMILIES = {"rod1": ["rod2", "rod3", "rod1_L1_200_L2_600"], "rod4": ["rod5", "rod6", "rod4_L1_420_L2_330"],
            "Y": ["Y_L1_260_L2_480"]}


def design(name):
    if name in FAMILY_OFF_GRID:
        from dataclasses import replace
        base, L1, L2 = FAMILY_OFF_GRID[name]
        return replace(design(base), L1_mm=L1, L2_mm=L2, name=name)
    spec = OFF_GRID.get(name) or PROBES.get(name) or THIN_PROBES.get(name)
    if spec is not None:
        return design_from_dict(dict({"format": "rodlab.rod/1", "name": name}, **spec))
    return resolve_design(name)


def solve_references(missing_only: bool = False) -> dict:
    from rodlab.fea import solid_compliance
    from rodlab.geometry import mesh_rod
    out = json.loads(REF.read_text()) if missing_only and REF.exists() else {}
    for name in dict.fromkeys(CALIBRATION_SET + VALIDATION_SET + list(FAMILY_OFF_GRID) + PROBE_SET + THIN_SET):
        if name in out:
            continue
        comp, res = solid_compliance(design(name), mesh_rod,
                                     error_estimate=False)
        out[name] = {"C_F": comp.C_F.tolist(), "C_g": comp.C_g.tolist(), "dofs": res.dofs,
                     "size_mm": comp.provenance["mesh"]["size_mm"]}
        print(name, res.dofs, np.diag(comp.C_F), flush=True)
        atomic_write_json(REF, out)
    return out


def rel_errors(name, ref, cal) -> np.ndarray:
    from rodlab.fea.frame import frame_errors
    return frame_errors(design(name), ref["C_F"], ref["C_g"], cal)


#: the constants of the global fit (shear and torsion stay at theory, 1)
GLOBAL_FIT = ("sleeve_end", "holder_end", "torsion_end", "bend_scale_in", "bend_scale_out", "bend_end",
              "bend_restraint", "holder_orthotropy", "holder_slenderness")


def fit(refs: dict):
    from rodlab.fea.frame import calibrate_frame
    names = CALIBRATION_SET + PROBE_SET
    return calibrate_frame([design(n) for n in names], [refs[n]["C_F"] for n in names],
                           [refs[n]["C_g"] for n in names], names=GLOBAL_FIT)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--solve", action="store_true", help="recompute every solid reference")
    ap.add_argument("--solve-missing", action="store_true", help="compute only the references not stored yet")
    args = ap.parse_args()
    if args.solve or args.solve_missing or not REF.exists():
        refs = solve_references(missing_only=args.solve_missing)
    else:
        refs = json.loads(REF.read_text())
    from rodlab.fea.frame import CALIBRATION, FrameCalibration
    cal = fit(refs)
    print(f"fitted: {cal}; in use: {CALIBRATION}")
    from rodlab.fea.frame import calibrate_frame
    for base, others in FAMILIES.items():
        fam = calibrate_frame([design(base)], [refs[base]["C_F"]], [refs[base]["C_g"]])
        print(f"-- family calibrated on {base} only: {fam}")
        for n in [base] + others:
            e = rel_errors(n, refs[n], fam)
            print(f"  {n:18s} max |err| {100 * np.abs(e).max():5.2f} %  rms {100 * np.sqrt(np.mean(e ** 2)):5.2f} %")
    for label, cset in (("uncalibrated (ASME k on the whole arc, fully effective sleeves)", FrameCalibration()),
                        ("in use", CALIBRATION)):
        print(f"-- {label}")
        for n in CALIBRATION_SET + PROBE_SET + VALIDATION_SET + THIN_SET:
            e = rel_errors(n, refs[n], cset)
            tag = "VAL" if n in VALIDATION_SET else ("out" if n in THIN_SET else "cal")
            rms = 100 * np.sqrt(np.mean(e ** 2))
            print(f"  {tag} {n:18s} max |err| {100 * np.abs(e).max():5.2f} %  rms {rms:5.2f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
