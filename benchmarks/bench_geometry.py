"""Benchmark: CAD + mesh of the paper's six rods at the default mesh size.

    python benchmarks/bench_geometry.py            # prints the table and writes docs/benchmarks/geometry.md

Goal (issue: geometry): CAD + mesh of one rod under 10 s on 2 cores.
"""
from __future__ import annotations

import os
import platform
import time
from pathlib import Path

from rodlab.core.design_io import resolve_design
from rodlab.core.fileio import atomic_write_text

OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "geometry.md"
GOAL_S = 10.0


def main() -> int:
    t_imp = time.perf_counter()
    from rodlab.geometry import build_cad, mesh_rod
    import build123d  # noqa: F401  (import cost reported separately)
    t_imp = time.perf_counter() - t_imp
    rows = []
    for i in range(1, 7):
        d = resolve_design(f"rod{i}")
        t0 = time.perf_counter()
        build_cad(d)
        t_cad = time.perf_counter() - t0
        t0 = time.perf_counter()
        rm = mesh_rod(d)
        t_mesh = time.perf_counter() - t0
        rows.append((d.name, t_cad, t_mesh, rm.stats["elements"], rm.stats["nodes"], rm.stats["size_mm"],
                     rm.stats["min_quality_sicn"]))
        print(f"{d.name}: CAD {t_cad:.2f} s, mesh {t_mesh:.2f} s, {rm.stats['elements']} tet10, "
              f"worst quality {rm.stats['min_quality_sicn']:.3f}")
    lines = ["# Benchmark: CAD + mesh", "",
             f"`python benchmarks/bench_geometry.py` on {platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}, {time.strftime('%Y-%m-%d')}. Goal: CAD + mesh of one rod "
             f"< {GOAL_S:g} s. Import of build123d/gmsh: {t_imp:.1f} s once per process (not counted).", "",
             "| rod | CAD s | mesh s | total s | tet10 elements | nodes | size mm | worst minSICN | goal |",
             "|---|---|---|---|---|---|---|---|---|"]
    for name, tc, tm, ne, nn, h, q in rows:
        lines.append(f"| {name} | {tc:.2f} | {tm:.2f} | {tc + tm:.2f} | {ne} | {nn} | {h:g} | {q:.3f} | "
                     f"{'met' if tc + tm < GOAL_S else 'MISSED'} |")
    lines.append("")
    atomic_write_text(OUT, "\n".join(lines))
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
