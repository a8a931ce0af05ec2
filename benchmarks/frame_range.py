"""Check: the frame model against solid FEA at the edges of the design range (``rodlab.core.design_range``).

The frame model's constants were fitted and checked on L1 150-450 mm, L2 250-600 mm, gamma 60-180 deg
(``fea/data/solid_reference.json``). This script checks the designs at the edges of the wider range that
``rodlab.core.design_range.VERIFIED_RANGE`` states (longest, shortest, sharpest bend, carbon and steel): the
largest relative error of the frame on every significant entry of C_F and C_g (|entry| > 2 % of its
matrix's largest). Needs the CAD extra (gmsh).

    python benchmarks/frame_range.py            # writes docs/benchmarks/frame_range.md
"""
from __future__ import annotations

import platform
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from pages import write_page  # noqa: E402

#: (label, built-in base, L1_mm, L2_mm, gamma_deg): the corners of VERIFIED_RANGE, and just outside it
CASES = (
    ("long carbon", "rod1", 800.0, 1200.0, 90.0),
    ("longest carbon", "rod1", 1200.0, 2000.0, 90.0),
    ("longest steel", "rod4", 1200.0, 2000.0, 90.0),
    ("shortest carbon", "rod1", 150.0, 250.0, 90.0),
    ("sharpest bend", "rod1", 300.0, 300.0, 60.0),
    ("sharpest bend, long", "rod4", 1200.0, 1500.0, 60.0),
    ("straight, long", "rod1", 1200.0, 800.0, 180.0),
    ("outside: shorter", "rod1", 145.0, 200.0, 90.0),        # the derived rod 1#: L1 >= 145 mm by its parts
    ("outside: sharper bend", "rod1", 300.0, 300.0, 45.0),
)


def _row(label, base, L1, L2, gamma) -> tuple[str, float]:
    from rodlab.core.design_io import resolve_design
    from rodlab.fea import frame_compliance, solid_compliance
    from rodlab.fea.frame import frame_errors
    from rodlab.geometry import mesh_rod
    d = replace(resolve_design(base), L1_mm=L1, L2_mm=L2, gamma_deg=gamma, name=f"{base} {L1:g}-{L2:g}-{gamma:g}")
    t0 = time.perf_counter()
    comp, _ = solid_compliance(d, mesh_rod, error_estimate=False)
    seconds = time.perf_counter() - t0
    worst = float(np.abs(frame_errors(d, comp.C_F, comp.C_g)).max())
    CF, Cg = frame_compliance(d)
    scaled = max(float(np.abs(mine - ref).max() / np.abs(ref).max()) for mine, ref in ((CF, comp.C_F), (Cg, comp.C_g)))
    return (f"| {label} | {base} | {L1:g} | {L2:g} | {gamma:g} | {comp.c_rod_um:.1f} | {100 * scaled:.2f} | "
            f"{100 * worst:.2f} | {seconds:.1f} |", scaled)


def main() -> None:
    from rodlab.core.design_range import VERIFIED_RANGE
    rows, worst = [], 0.0
    for case in CASES:
        row, w = _row(*case)
        rows.append(row)
        if not case[0].startswith("outside"):
            worst = max(worst, w)
        print(row, flush=True)
    rng = ", ".join(f"{k} {lo:g}-{hi:g} {u}" for k, (lo, hi, u) in VERIFIED_RANGE.items())
    lines = ["# Frame model at the edges of the design range", "",
             f"`python benchmarks/frame_range.py` on {platform.node()} ({platform.machine()}), "
             f"{time.strftime('%Y-%m-%d')}. The frame model (the study's and sweep's default) against the solid "
             "FEA (default mesh, half model, no error estimate) on the corners of the range rodlab states as "
             f"checked (`rodlab.core.design_range.VERIFIED_RANGE`: {rng}); outside it a design loads with a warning "
             "naming the key and the range. Parts as the base rod's (1#: carbon, 4#: steel).", "",
             "Errors of the frame: *of largest* = largest |frame - solid| over C_F and C_g, each divided by its "
             "matrix's largest entry (what moves the ball); *per entry* = largest relative error of a "
             "significant entry (|entry| > 2 % of its matrix's largest; small coupling terms of short rods).", "",
             "| case | base | L1 mm | L2 mm | gamma deg | solid c_rod um | frame error, of largest % | "
             "frame error, per entry % | solid s |",
             "|---|---|---|---|---|---|---|---|---|", *rows, "",
             f"Largest error of the frame inside the range, relative to the matrix's largest entry: "
             f"{100 * worst:.2f} %."]
    write_page(HERE.parent / "docs" / "benchmarks" / "frame_range.md", lines, HERE / "frame_range_notes.md")


if __name__ == "__main__":
    main()
