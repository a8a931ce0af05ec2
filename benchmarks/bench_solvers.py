"""Benchmark: sparse direct solvers that come from pip, on the solid model's own matrices (rod 1#, the two
half problems of the default mesh), as the issue on fresh-machine speed asks.

    python benchmarks/bench_solvers.py                  # the candidates installed here
    pip install cholespy && python benchmarks/bench_solvers.py   # add one (install it in the benchmark's venv)

Each candidate runs in its own process (peak memory is its own): analysis once, numerical factorisation of
both matrices (same pattern, different held DOFs), six right-hand sides each, as ``fea.solver`` uses them.
Accuracy: relative residual ``|K u - f| / |f|`` and the largest difference of the solution from SuperLU's.
Writes docs/benchmarks/solvers.md.
"""
from __future__ import annotations

import importlib.metadata as md
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
from pages import write_page  # noqa: E402  (beside this script, on sys.path when it runs)
OUT = ROOT / "docs" / "benchmarks" / "solvers.md"

#: candidate -> (module to import, distributions whose installed size counts, release / maintenance note)
CANDIDATES = {
    "pardiso": ("pypardiso", ["pypardiso", "mkl", "intel-openmp", "tbb", "tcmlib", "umf"],
                "pypardiso 0.4.x (2025) on Intel's MKL wheels (released monthly); x86-64 Linux and Windows"),
    "cholmod": ("sksparse.cholmod", ["scikit-sparse"],
                "scikit-sparse: sdist only on PyPI, needs a system SuiteSparse (apt libsuitesparse-dev)"),
    "cholespy": ("cholespy", ["cholespy"],
                 "cholespy 2.x (2026): CHOLMOD in a wheel, but with reference (netlib) BLAS"),
    "sksparse_minimal": ("sksparse_minimal", ["sksparse-minimal"],
                         "sksparse-minimal 0.3 (2025): cholespy's CHOLMOD build, same reference BLAS"),
    "superlu": ("scipy.sparse.linalg", ["scipy"], "SciPy's SuperLU: always there; LU, ignores symmetry"),
}

_CAPTURE = r"""
import sys, numpy as np, scipy.sparse as sp
import rodlab.fea.solver as S
from rodlab import resolve_design
from rodlab.fea.compute import DEFAULT_GRADING, default_solid_size_mm
from rodlab.fea.solid import solve_compliance
from rodlab.geometry import mesh_rod
mats = []
orig = S.PatternSolver.factor
def factor(self, A):
    mats.append(sp.csc_matrix(A).copy())
    return orig(self, A)
S.PatternSolver.factor = factor
d = resolve_design("rod1")
rm = mesh_rod(d, size_mm=default_solid_size_mm(d), grading=DEFAULT_GRADING, half=True)
solve_compliance(d, rm, backend="superlu")
for i, A in enumerate(mats):
    sp.save_npz(f"{sys.argv[1]}/K{i}.npz", A)
"""

_RUN = r"""
import json, resource, sys, time, numpy as np, scipy.sparse as sp
which, d = sys.argv[1], sys.argv[2]
mats = [sp.load_npz(f"{d}/K{i}.npz").tocsc() for i in range(2)]
for A in mats: A.sort_indices()
n = mats[0].shape[0]
B = np.random.default_rng(0).standard_normal((n, 6))
t0 = time.perf_counter()
if which == "pardiso":
    import rodlab.fea.solver as S
    def tril_keep_zeros(A):    # the held DOFs' explicit zeros stay: one pattern for both matrices
        col = np.repeat(np.arange(n), np.diff(A.indptr)); keep = A.indices >= col
        ptr = np.concatenate([[0], np.cumsum(np.bincount(col[keep], minlength=n))])
        return sp.csc_matrix((A.data[keep], A.indices[keep], ptr), shape=A.shape)
    lower = [tril_keep_zeros(A) for A in mats]
    ps = S.PatternSolver(lower[0], "pardiso"); solves = []
    for L in lower:
        f = ps.factor(L); solves.append(f(B))
elif which == "cholmod":
    from sksparse.cholmod import analyze
    sym = analyze(mats[0]); solves = []
    for A in mats:
        f = sym.cholesky(A); solves.append(f(B))
elif which in ("cholespy", "sksparse_minimal"):
    solves = []
    for A in mats:
        if which == "cholespy":
            import cholespy
            s = cholespy.CholeskySolverD(n, A.indptr.astype(np.int32), A.indices.astype(np.int32), A.data,
                                         cholespy.MatrixType.CSC)
            X = np.zeros_like(B); s.solve(np.ascontiguousarray(B), X)
        else:
            from sksparse_minimal import SparseCholesky
            X = SparseCholesky(A).solve_A(B)
        solves.append(X)
else:
    from scipy.sparse.linalg import splu
    solves = []
    for A in mats:
        lu = splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        solves.append(lu.solve(B))
wall = time.perf_counter() - t0
res = max(float(np.abs(A @ X - B).max() / np.abs(B).max()) for A, X in zip(mats, solves))
np.save(f"{d}/{which}.npy", np.stack(solves))
print(json.dumps({"wall_s": wall, "residual": res, "peak_GB": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6}))
"""


def _installed_mb(dists: list[str]) -> float | None:
    total = 0
    for name in dists:
        try:
            files = md.files(name) or []
        except md.PackageNotFoundError:
            if name == dists[0]:
                return None
            continue
        total += sum(f.locate().stat().st_size for f in files if f.locate().exists())
    return total / 1e6


def _available(module: str) -> bool:
    return subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True).returncode == 0


def main() -> int:
    import numpy as np
    import scipy.sparse as sp
    rows = []
    with tempfile.TemporaryDirectory(prefix="rodlab-solvers-") as d:
        subprocess.run([sys.executable, "-c", _CAPTURE, d], check=True)
        for name, (module, dists, note) in CANDIDATES.items():
            if not _available(module):
                rows.append((name, None, None, None, None, None, note + " - not installed here"))
                print(f"{name:<18} not installed")
                continue
            p = subprocess.run([sys.executable, "-c", _RUN, name, d], capture_output=True, text=True)
            if p.returncode:
                rows.append((name, None, None, None, None, _installed_mb(dists), note + f" - failed: "
                             f"{p.stderr.strip().splitlines()[-1] if p.stderr.strip() else p.returncode}"))
                continue
            r = json.loads(p.stdout.strip().splitlines()[-1])
            rows.append([name, r["wall_s"], r["peak_GB"], r["residual"], None, _installed_mb(dists), note])
            print(f"{name:<18} {r['wall_s']:6.2f} s {r['peak_GB']:5.2f} GB residual {r['residual']:.1e}")
        dofs = sp.load_npz(Path(d) / "K0.npz").shape[0]
        ref = Path(d) / "superlu.npy"
        if ref.exists():
            X0 = np.load(ref)
            for row in rows:
                f = Path(d) / f"{row[0]}.npy"
                if row[1] is not None and f.exists():
                    row[4] = float(np.abs(np.load(f) - X0).max() / np.abs(X0).max())
    from rodlab.fea.solver import available_backend
    lines = ["# Sparse direct solvers from pip (rod 1#, solid model)", "",
             f"Generated by `python benchmarks/bench_solvers.py` on {time.strftime('%Y-%m-%d')}, "
             f"{platform.machine()}, {os.cpu_count()} cores. Both half problems of rod 1#'s default mesh ({dofs} DOFs "
             "each): analysis, two numerical factorisations, six right-hand sides each; each solver in its own "
             f"process. The default here is `{available_backend()}`.", "",
             "| solver | time [s] | peak [GB] | residual | max diff vs SuperLU | installed [MB] | notes |",
             "|---|---:|---:|---:|---:|---:|---|"]

    def f(v, fmt):
        return "" if v is None else format(v, fmt)
    for name, wall, gb, res, diff, mb, note in rows:
        lines.append(f"| {name} | {f(wall, '.2f')} | {f(gb, '.2f')} | {f(res, '.1e')} | {f(diff, '.1e')} | "
                     f"{f(mb, '.0f')} | {note} |")
    write_page(OUT, lines, ROOT / "benchmarks" / "solvers_notes.md")
    return 0


if __name__ == "__main__":
    sys.exit(main())
