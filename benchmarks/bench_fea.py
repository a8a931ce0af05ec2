"""Benchmark: solid FEA of rod 1# (time, peak memory, DOFs, error vs a refined mesh), CalculiX on the same
mesh, the frame model per design, and a 1000-design frame sweep.

    python benchmarks/bench_fea.py        # prints and writes docs/benchmarks/fea.md (~3-4 min)

Goals (issue: fea): solid C_F + C_g of rod 1# within 0.15 % of converged in <= 5 s and <= 2 GB on 2 cores;
>= 5x faster than CalculiX at equal accuracy; frame <= 5 ms per design; 1000-design frame sweep <= 30 s.
"""
from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "fea.md"
NOTES = ["## Notes", "",
         "- **Goal met in the environment of README command 1** (a fresh venv, no apt step): the solver is Intel",
         "  MKL PARDISO from pip (pypardiso + the mkl wheels), 0.11 % from converged (goal 0.15 %) in under 5 s",
         "  from the design (the table's median of 5 runs and their range; mesh ~1.2 s + FEA ~2.5 s), ~13x",
         "  faster than CalculiX on the same mesh; peak memory ~1.03 GB (goal 1 GB: missed, see Memory).",
         "  The whole CLI command adds ~3 s of imports (build123d 2.2 s of it, scikit-learn 0.75 s",
         "  of those, pulled in by build123d): see docs/benchmarks/speed.md. VMs differ, and so does one VM from",
         "  hour to hour (see the machine check).",
         "- Where the FEA time goes with PARDISO (rod 1#, 91k DOFs per half): one METIS analysis of the shared",
         "  pattern ~0.5 s (OpenMP-parallel nested dissection, iparm[1] = 3), ~0.25 s per numerical",
         "  factorisation on 2 cores, 0.05-0.1 s per solve of its cases; assembly ~0.2-0.4 s (first touch of",
         "  fresh memory), basis and loads ~0.2 s; loading MKL ~0.3 s once per process. gmsh sets the process's",
         "  OpenMP thread count to 1 while meshing; rodlab sets MKL's back to the cores it may use before each",
         "  PARDISO call (that had halved the factorisation speed).",
         "- History. 2026-11-24: PARDISO from pip replaces CHOLMOD from apt as the fast path (CHOLMOD, node-",
         "  ordered, OpenBLAS: ~0.8 s per factorisation; SuperLU, the fallback: ~8 s; the CHOLMOD wheels",
         "  cholespy / sksparse-minimal ship the reference BLAS: ~3.5 s; docs/benchmarks/solvers.md).",
         "  2026-11-23: the nodes ordered on the vertex graph for CHOLMOD, K's upper block triangle assembled",
         "  straight into the ordered block list; METIS on the node graph with K assembled in that numbering,",
         "  clamp and plane held in place instead of sliced copies. 2026-11-22: the symmetry half-model (two",
         "  half-size factorisations sharing one analysis; exact), grading restricted to the tubes with a finer",
         "  bend (91k DOFs reach 0.11 %), gmsh's 1-D size integration at 1e-3, assembly in 2000-element chunks.",
         "- Routes that remain: swept quadratic hexahedra through the thin tube walls (far fewer DOFs),",
         "  substructuring the stiff holders and the ball, and for the CLI a mesher that does not import",
         "  build123d (gmsh's own OpenCASCADE kernel).",
         "- Memory: the default row's peak (~1.03 GB) is 0.45 GB of imports (build123d, OpenCASCADE, scikit-learn",
         "  pulled in by build123d) plus ~0.6 GB for the FEA, of which PARDISO's own ~0.32 GB (MKL reports 110 MB",
         "  permanent + 210 MB factor for each half problem). The 1 GB goal is missed by ~3-5 %; CHOLMOD's",
         "  node-ordered factor was ~0.2 GB smaller (0.84 GB peak), at twice the factorisation time.", ""]

_SOLID = r"""
import json, resource, sys, time
t0 = time.perf_counter()
from rodlab import resolve_design
from rodlab.geometry import mesh_rod
from rodlab.fea import solid_compliance
import build123d, gmsh, skfem  # noqa: F401  (imported lazily by the mesher: counted apart, once per process)
t_imp = time.perf_counter() - t0
size, near, growth, bend, sym = (float(v) for v in sys.argv[1:6])
d = resolve_design("rod1")
t0 = time.perf_counter()
comp, res = solid_compliance(d, mesh_rod, size_mm=size,
                             grading=(near, growth, bend) if near < 1 else None, error_estimate=False,
                             symmetry=bool(sym))
wall = time.perf_counter() - t0
print(json.dumps({"C_F": comp.C_F.tolist(), "C_g": comp.C_g.tolist(), "dofs": res.dofs, "wall_s": wall,
                  "import_s": t_imp,
                  "timings": comp.provenance["timings_s"], "solver": res.backend,
                  "peak_MB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}))
"""

_CCX = r"""
import json, sys, time, numpy as np
from rodlab import resolve_design
from rodlab.geometry import mesh_rod
from rodlab.fea import solve_compliance
from rodlab.fea.calculix import run_ccx_compliance
d = resolve_design("rod1")
half = mesh_rod(d, size_mm=float(sys.argv[1]), grading=tuple(float(v) for v in sys.argv[2:5]), half=True)
whole = half.mirrored()           # the same discretisation as the half model, for CalculiX and our whole solve
solve_compliance(d, half)         # warm-up (first CHOLMOD call loads its libraries)
t0 = time.perf_counter(); ours = solve_compliance(d, half); t_ours = time.perf_counter() - t0
t0 = time.perf_counter(); ours_w = solve_compliance(d, whole); t_whole = time.perf_counter() - t0
t0 = time.perf_counter(); theirs = run_ccx_compliance(d, whole); t_ccx = time.perf_counter() - t0
big = np.abs(ours.C_F) > 1e-3 * np.abs(ours.C_F).max()
print(json.dumps({"t_ours_solve_s": t_ours, "t_whole_solve_s": t_whole, "t_ccx_s": t_ccx, "dofs": ours.dofs,
                  "dofs_whole": ours_w.dofs, "max_rel_diff": float(np.max(np.abs(theirs[big] / ours.C_F[big] - 1))),
                  "half_vs_whole": float(np.max(np.abs(ours_w.C_F - ours.C_F)) / np.abs(ours.C_F).max())}))
"""


def machine_check() -> float:
    """Seconds for a fixed dense workload (20 Cholesky factorisations of a 1500 x 1500 SPD matrix on the
    default BLAS threads): shows how fast this VM was while the benchmark ran (shared hosts vary)."""
    import numpy as np
    A = np.random.default_rng(0).standard_normal((1500, 1500))
    A = A @ A.T + 1500 * np.eye(1500)
    np.linalg.cholesky(A)                                   # warm-up: BLAS threads, first touch
    t0 = time.perf_counter()
    for _ in range(20):
        np.linalg.cholesky(A)
    return time.perf_counter() - t0


def run(code: str, *args) -> dict:
    r = subprocess.run([sys.executable, "-c", code, *map(str, args)], capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(r.stderr[-2000:])
    return json.loads(r.stdout.strip().splitlines()[-1])


#: the solid-model rows: label, run(_SOLID, size, ...) arguments
_ROWS = (("**default**: half model, graded, size 6 mm (1.8 mm at section changes, bend 4.2 mm)",
          (6.0, 0.3, 0.3, 0.7, 1)),
         ("the same settings on the whole rod (`symmetry=False`)", (6.0, 0.3, 0.3, 0.7, 0)),
         ("half model, graded, size 7 mm", (7.0, 0.3, 0.3, 0.7, 1)),
         ("half model, uniform 4 mm (2 x wall)", (4.0, 1.0, 0.0, 1.0, 1)))


def _measure_rows() -> list:
    """Each row's run; the goal's row (default) as the median of 5, since one run varies by +-20 %."""
    measured = []
    for label, args in _ROWS:
        if args == _ROWS[0][1]:
            runs = sorted((run(_SOLID, *args) for _ in range(5)), key=lambda r: r["wall_s"])
            r = dict(runs[2], wall_range=(runs[0]["wall_s"], runs[-1]["wall_s"]))
        else:
            r = run(_SOLID, *args)
        measured.append((label, r))
        print(label, r["dofs"], r["wall_s"])
    return measured


def _reference():
    """Richardson extrapolation of uniform 2.5 mm and 2.0 mm half meshes (observed order 3.4): (C, run a, run b)."""
    import numpy as np
    ra, rb = run(_SOLID, 2.5, 1.0, 0.0, 1.0, 1), run(_SOLID, 2.0, 1.0, 0.0, 1.0, 1)
    f = (2.5 / 2.0) ** 3.4 - 1.0
    ref = {k: (np.array(rb[k]) + (np.array(rb[k]) - np.array(ra[k])) / f).tolist() for k in ("C_F", "C_g")}
    print("reference", ra["dofs"], rb["dofs"])
    return ref, ra, rb


def _errors(measured, ref) -> list:
    """(label, run, C_F error, C_g error) over the entries larger than 0.1 % of the largest."""
    import numpy as np
    rows = []
    for label, r in measured:
        CF, CR = np.array(r["C_F"]), np.array(ref["C_F"])
        big = np.abs(CR) > 1e-3 * np.abs(CR).max()
        err = float(np.max(np.abs(CF[big] / CR[big] - 1)))
        gerr = float(np.max(np.abs(np.array(r["C_g"])[big] / np.array(ref["C_g"])[big] - 1)))
        rows.append((label, r, err, gerr))
        print(label, r["dofs"], r["wall_s"], err)
    return rows


def _solid_section(rows, ra, rb) -> list[str]:
    lines = ["## Solid C_F + C_g of rod 1# (six load cases)", "",
             f"Reference: Richardson extrapolation (order 3.4) of uniform 2.5 mm ({ra['dofs']} DOFs) and 2.0 mm "
             f"({rb['dofs']} DOFs, {rb['wall_s']:.0f} s) half meshes. Error = largest relative difference over the "
             f"entries larger than 0.1 % of the matrix's largest.", "",
             "Wall time from the design to C_F and C_g, imports excluded (build123d, gmsh and scikit-fem load "
             f"once per process: {rows[0][1]['import_s']:.1f} s here).", "",
             "| mesh | DOFs | wall s (mesh + FEA) | assembly s | factorise s | peak MB | solver | C_F err | C_g err |",
             "|---|---|---|---|---|---|---|---|---|"]
    for label, r, err, gerr in rows:
        t = r["timings"]
        spread = (f" (median of 5: {r['wall_range'][0]:.1f}-{r['wall_range'][1]:.1f})" if "wall_range" in r else "")
        lines.append(f"| {label} | {r['dofs']} | {r['wall_s']:.1f} ({t['mesh']:.1f} + {t['total']:.1f}){spread} | "
                     f"{t['assembly']:.2f} | {t['factorize']:.2f} | {r['peak_MB']:.0f} | {r['solver']} | "
                     f"{100 * err:.3f} % | {100 * gerr:.3f} % |")
    return lines


def _calculix_section() -> list[str]:
    c = run(_CCX, 6.0, 0.3, 0.3, 0.7)
    return ["", "## CalculiX on the same discretisation", "",
            f"The default half mesh mirrored into the whole rod ({c['dofs_whole']} DOFs; our half model solves "
            f"the same discretisation exactly: largest difference {c['half_vs_whole']:.1e} of max |C_F|). ccx "
            f"(C3D10, `*RIGID BODY` ball, three `*STEP`s for C_F only) {c['t_ccx_s']:.1f} s; rodlab "
            f"{c['t_ours_solve_s']:.1f} s for all six load cases on the half model ({c['dofs']} DOFs), "
            f"{c['t_whole_solve_s']:.1f} s on the whole mesh: "
            f"{c['t_ccx_s'] / c['t_ours_solve_s']:.1f}x faster for three load cases, "
            f"{2 * c['t_ccx_s'] / c['t_ours_solve_s']:.1f}x for the six; largest difference in C_F "
            f"{100 * c['max_rel_diff']:.3f} %.", ""]


def _frame_section() -> list[str]:
    """The frame model per design (mean of 300) and a 1000-design frame sweep on 2 Dask workers."""
    import numpy as np
    from rodlab import resolve_design
    from rodlab.fea.frame import frame_compliance
    from rodlab.fea.sweep import run_sweep
    d = resolve_design("rod1")
    frame_compliance(d)
    n = 300
    t0 = time.perf_counter()
    for _ in range(n):
        frame_compliance(d)
    t_frame = (time.perf_counter() - t0) / n * 1e3
    t0 = time.perf_counter()
    df = run_sweep(d, np.linspace(150, 450, 40), np.linspace(300, 650, 25), model="frame", workers=2, batch=50)
    t_sweep = time.perf_counter() - t0
    return ["## Frame model and sweeps", "",
            f"- frame model: {t_frame:.2f} ms per design (goal <= 5 ms)",
            f"- {len(df)}-design frame sweep on a 2-worker Dask LocalCluster: {t_sweep:.1f} s including the "
            f"cluster start (goal <= 30 s)", ""]


def _machine_section(speed0: float) -> list[str]:
    return ["## Machine check", "",
            f"A fixed dense workload (20 Cholesky factorisations of 1500 x 1500, numpy's BLAS) took "
            f"{speed0:.2f} s before the runs and {machine_check():.2f} s after them: compare it between "
            "VMs and runs before comparing the times above.", ""]


def main() -> int:
    from rodlab.core.fileio import atomic_write_text
    lines = ["# Benchmark: FEA", "",
             f"`python benchmarks/bench_fea.py` on {platform.machine()}, {os.cpu_count()} cores, Python "
             f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}.", ""]
    machine_check()                                   # the first call in a process is slower
    speed0 = machine_check()
    # the rows first (the reference's large runs leave memory the next runs must fetch again)
    measured = _measure_rows()
    ref, ra, rb = _reference()
    lines += _solid_section(_errors(measured, ref), ra, rb)
    lines += _calculix_section() + _frame_section() + _machine_section(speed0)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    atomic_write_text(OUT, "\n".join(lines + NOTES))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
