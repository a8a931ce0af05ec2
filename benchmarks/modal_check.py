"""Check: the study's natural frequencies (beam frame, lumped masses) against the solid rod's modal analysis.

For the six built-in rods: the first four frequencies of the frame model (:func:`rodlab.fea.frame_frequencies`)
and of the solid (:func:`rodlab.fea.solid_frequencies`, scikit-fem, consistent mass, the default solid mesh),
their ratio, and which modes are symmetric about the bend plane. Needs the CAD extra (gmsh).

    python benchmarks/modal_check.py            # writes docs/benchmarks/modal.md
"""
from __future__ import annotations

import platform
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
from pages import write_page  # noqa: E402

MODES = 4
RODS = ("rod1", "rod2", "rod3", "rod4", "rod5", "rod6")


def _row(name: str) -> tuple[list[str], float]:
    from rodlab.core.design_io import resolve_design
    from rodlab.fea import frame_frequencies, solid_frequencies
    from rodlab.geometry import mesh_rod
    d = resolve_design(name)
    t0 = time.perf_counter()
    solid = solid_frequencies(d, mesh_rod(d, half=True), modes=MODES)
    seconds = time.perf_counter() - t0
    frame = frame_frequencies(d, modes=MODES)
    dev = frame / solid.frequencies_Hz - 1.0
    cells = [d.name, f"{solid.dofs}"]
    cells += [f"{s:.1f} / {f:.1f} ({100 * e:+.1f} %) {'S' if sym else 'A'}"
              for s, f, e, sym in zip(solid.frequencies_Hz, frame, dev, solid.symmetric)]
    return cells + [f"{seconds:.1f}"], float(np.abs(dev).max())


def main() -> None:
    rows, worst = [], 0.0
    for name in RODS:
        cells, dev = _row(name)
        rows.append("| " + " | ".join(cells) + " |")
        worst = max(worst, dev)
        print(rows[-1])
    lines = ["# Natural frequencies: frame model against the solid", "",
             f"`python benchmarks/modal_check.py` on {platform.node()} ({platform.machine()}), "
             f"{time.strftime('%Y-%m-%d')}. The rod clamped at the flange face with its ball; solid = scikit-fem "
             "modal analysis of the default half mesh (symmetric and antisymmetric problems), frame = the study's "
             "model (`rodlab.fea.frame_frequencies`).", "",
             "Each cell: solid Hz / frame Hz (frame deviation), S = mode symmetric about the bend plane (in "
             "plane), A = antisymmetric (out of plane, torsion).", "",
             "| rod | solid DOFs | mode 1 | mode 2 | mode 3 | mode 4 | solid s |",
             "|---|---|---|---|---|---|---|", *rows, "",
             f"Largest deviation of the frame over the six rods and four modes: {100 * worst:.1f} %. The stated "
             "tolerance (tests/test_modal.py, docs/study.md) is 3 %."]
    write_page(HERE.parent / "docs" / "benchmarks" / "modal.md", lines, HERE / "modal_notes.md")


if __name__ == "__main__":
    main()
