"""Parameter covariance of a least-squares fit that does not hide what the data cannot see.

``np.linalg.pinv(J.T @ J)`` drops the directions whose singular values fall below round-off, and gives them a
variance of *zero*: a parameter the data barely see would be reported as the best known. Here the columns are
scaled first (parameters in mm, mrad and urad/(N m) differ by orders of magnitude) and a parameter with a
component along a direction the data do not see (singular value below ``rcond`` of the largest) gets an
infinite variance.
"""
from __future__ import annotations

import numpy as np

__all__ = ["parameter_covariance", "correlation"]


def parameter_covariance(J: np.ndarray, rcond: float = 1e-10) -> np.ndarray:
    """``(J^T J)^-1`` of a whitened Jacobian ``J`` (rows: residuals, columns: parameters), shape=(P, P); the
    variance of a parameter the data do not see is ``inf`` (its covariances with the others ``nan``)."""
    J = np.asarray(J, float)
    P = J.shape[1]
    if P == 0:
        return np.zeros((0, 0))
    norms = np.linalg.norm(J, axis=0)
    norms = np.where(norms > 0, norms, 1.0)
    _, s, Vt = np.linalg.svd(J / norms, full_matrices=False)
    seen = s > rcond * max(s[0], 1e-300) if s.size else np.zeros(0, bool)
    V = Vt[seen].T
    cov = (V / s[seen] ** 2) @ V.T / np.outer(norms, norms)
    unseen = 1.0 - (Vt[seen] ** 2).sum(axis=0) > 1e-6     # a component outside what the data see (also M < P)
    if unseen.any():
        cov[unseen, :] = np.nan
        cov[:, unseen] = np.nan
        cov[unseen, unseen] = np.inf
    return cov


def correlation(cov: np.ndarray) -> np.ndarray:
    """Correlation matrix of ``cov``; rows of a parameter with infinite or zero variance are ``nan``."""
    sig = np.sqrt(np.diag(cov))
    ok = np.isfinite(sig) & (sig > 0)
    d = np.where(ok, sig, np.nan)
    return cov / np.outer(d, d)
