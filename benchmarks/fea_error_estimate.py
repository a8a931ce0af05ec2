"""Benchmark: how good is the solid FEA's estimate of its own discretisation error?

    python benchmarks/fea_error_estimate.py [DESIGN:FACTORS ...]     (default rod1:1.5,1,0.667,0.444 rod5:1.5,1,0.667)

For each design, solves on its default graded half mesh scaled by each factor of the default size and compares
both estimates ``rodlab fea`` offers with the error against a reference:

- recovery (the default): stress recovery on the solve's own mesh (``fea/error_estimate.py``), signed;
- Richardson: the solve at this size and at 1.5 x this size, assumed order 3 (the default before 2026-11-27);
- the reference: the two finest solves, Richardson-extrapolated with the order observed on the three finest.

Writes docs/benchmarks/fea_error_estimate.md. One process, about 2 minutes on 2 cores.
"""
from __future__ import annotations

import datetime
import platform
import sys
import time
from pathlib import Path

import numpy as np

from rodlab.core.design_io import resolve_design
from rodlab.fea.compute import DEFAULT_GRADING, RICHARDSON_ORDER, default_solid_size_mm
from rodlab.fea.solid import solve_compliance
from rodlab.geometry import mesh_rod

OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "fea_error_estimate.md"
DEFAULT = ("rod1:1.5,1,0.667,0.444", "rod5:1.5,1,0.667,0.444")


def solve(design, h: float) -> dict:
    """One graded half-mesh solve with the recovery estimate: C_F, its estimated error, DOFs, the estimate's time."""
    rm = mesh_rod(design, size_mm=h, grading=DEFAULT_GRADING, half=True)
    res = solve_compliance(design, rm, error_estimate=True)
    return {"h": h, "dofs": res.dofs, "C_F": res.C_F, "E": res.error_matrix[:3, :3],
            "t_est": res.timings_s["error_estimate"], "t_total": res.timings_s["total"]}


def reference(runs: list) -> tuple[np.ndarray, float]:
    """C_F extrapolated from the two finest runs with the order observed on the three finest (diagonal mean)."""
    a, b, c = runs[-3:]                                            # coarse -> fine
    r1, r2 = a["h"] / b["h"], b["h"] / c["h"]
    d1, d2 = np.diag(b["C_F"] - a["C_F"]), np.diag(c["C_F"] - b["C_F"])
    observed = float(np.mean(np.log(np.abs(d1 / d2)) / np.log(r1 if np.isclose(r1, r2) else np.sqrt(r1 * r2))))
    order = min(max(observed, 1.0), 6.0)
    return c["C_F"] + (c["C_F"] - b["C_F"]) / (r2 ** order - 1.0), observed


def rows_for(name: str, factors: list[float]) -> tuple[list[str], float]:
    d = resolve_design(name)
    h0 = default_solid_size_mm(d)
    runs = [solve(d, h0 * f) for f in sorted(factors, reverse=True)]
    ref, order = reference(runs)
    scale = np.abs(ref).max()
    out = []
    for i, r in enumerate(runs):
        true = np.diag(ref - r["C_F"])
        rec = np.diag(r["E"])
        rich = (np.abs(np.diag(r["C_F"] - runs[i - 1]["C_F"])) / (1.5 ** RICHARDSON_ORDER - 1.0)
                if i > 0 and np.isclose(runs[i - 1]["h"] / r["h"], 1.5, rtol=0.01) else None)
        eff = lambda est: " / ".join(f"{x:.2f}" for x in est / true)           # noqa: E731
        out.append(f"| {name} | {r['h']:.2f}{' (default)' if np.isclose(r['h'], h0) else ''} | {r['dofs']} | "
                   f"{100 * np.abs(true).max() / scale:.3f} % | {100 * np.abs(rec).max() / scale:.3f} % | {eff(rec)} | "
                   + (f"{100 * rich.max() / scale:.3f} % | {eff(rich)} | " if rich is not None else "- | - | ")
                   + f"{100 * np.abs(np.diag(ref - r['C_F'] - r['E'])).max() / scale:.3f} % | {r['t_est']:.2f} / "
                   f"{r['t_total']:.2f} |")
        print(out[-1], flush=True)
    return out, order


def main(argv: list[str]) -> None:
    specs = argv or list(DEFAULT)
    t0 = time.perf_counter()
    lines, orders = [], []
    for spec in specs:
        name, facs = spec.split(":")
        rows, order = rows_for(name, [float(f) for f in facs.split(",")])
        lines += rows
        orders.append(f"{name} {order:.2f}")
    head = [
        "# The solid FEA's estimate of its own discretisation error",
        "",
        f"`python benchmarks/fea_error_estimate.py` on {platform.machine()}, Python {platform.python_version()}, "
        f"{datetime.date.today()} ({time.perf_counter() - t0:.0f} s). Graded half meshes at factors of each design's "
        f"default size; C_F's diagonal (xx / yy / zz). Reference: the two finest solves extrapolated with the order "
        f"observed on the three finest ({', '.join(orders)}; an order below 1 is taken as 1). Errors are relative "
        f"to max|C_F|; the effectivity is "
        f"estimate / (reference - computed) per diagonal entry (1 is exact; below 1 the estimate is optimistic). "
        f"The finest rows are part of the reference and their 'true' error is only what the extrapolation adds.",
        "",
        "| design | size [mm] | DOFs | error vs reference | recovery estimate | its effectivity xx / yy / zz | "
        "Richardson (h, 1.5 h) | its effectivity | left after adding the recovery estimate | estimate / solve [s] |",
        "|---|---:|---:|---:|---:|---|---:|---|---:|---|",
    ]
    OUT.write_text("\n".join(head + lines) + "\n\n" + NOTES, encoding="utf-8")
    print("wrote", OUT)


NOTES = (Path(__file__).with_name("fea_error_estimate_notes.md").read_text(encoding="utf-8")
         if Path(__file__).with_name("fea_error_estimate_notes.md").exists() else "")

if __name__ == "__main__":
    main(sys.argv[1:])
