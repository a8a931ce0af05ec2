"""Sparse SPD solves with one factorisation for many right-hand sides.

Fast path: CHOLMOD (``scikit-sparse`` built against SuiteSparse, e.g. Debian's ``libsuitesparse-dev``).
Pure-pip fallback: SciPy's SuperLU with a symmetric ordering (more memory and time; fine up to a few
hundred thousand DOFs on 24 GB).
"""
from __future__ import annotations

import logging

import numpy as np
import scipy.sparse as sp

__all__ = ["factorize", "available_backend"]

log = logging.getLogger(__name__)


def available_backend() -> str:
    """``"cholmod"`` when scikit-sparse imports, else ``"superlu"``."""
    try:
        from sksparse.cholmod import cholesky  # noqa: F401
        return "cholmod"
    except Exception:  # ImportError, or a broken shared library
        return "superlu"


def factorize(K: sp.spmatrix, backend: str | None = None):
    """Factorise an SPD matrix; return ``(solve, backend)`` where ``solve(B)`` takes shape (n,) or (n, k)."""
    backend = backend or available_backend()
    Kc = sp.csc_matrix(K)
    if backend == "cholmod":
        from sksparse.cholmod import cholesky
        f = cholesky(Kc)
        return (lambda B: f(np.asarray(B))), backend
    from scipy.sparse.linalg import splu
    lu = splu(Kc, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return (lambda B: lu.solve(np.asarray(B))), "superlu"
