"""Calibrate the frame model's constants against the solid model, and validate them.

    python scripts/calibrate_frame.py --solve   # (re)compute the solid references (~15 min, needs cad extra)
    python scripts/calibrate_frame.py --solve-missing   # only the references not stored yet
    python scripts/calibrate_frame.py           # fit on the calibration set and the part probes, report the rest

The designs are versioned data (``fea/data/reference_designs.json``, read by
:mod:`rodlab.fea.reference_designs`); the solid references (graded curved-P2 mesh at the default size) are
stored in ``fea/data/solid_reference.json`` so that tests can compare the frame model with them cheaply.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_json

from rodlab.fea.reference_designs import reference_design as design
from rodlab.fea.reference_designs import reference_sets

REF = Path(__file__).resolve().parents[1] / "fea" / "data" / "solid_reference.json"
_SETS = reference_sets()
CALIBRATION_SET, VALIDATION_SET = _SETS["calibration"], _SETS["validation"]
#: part probes (one joint each), fitted with the calibration set; thin walls: not fitted, reported
PROBE_SET, THIN_SET = _SETS["probes"], _SETS["thin"]
#: per-family calibration: each base with its members (off-grid ones: the same parts at other L1 / L2)
FAMILIES = _SETS["families"]
FAMILY_OFF_GRID = [m for members in FAMILIES.values() for m in members if "_L1_" in m]


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
