"""Bounded least squares over subsets of a term library, from sufficient statistics.

Every hypothesis term contributes columns to one design matrix ``X`` (n x p). The Gram matrix ``X^T X`` and
``X^T r`` are formed once (overall and per cross-validation fold), so fitting any subset of terms with physical
bounds costs O(k^3) instead of O(n k^2): the bounded problem ``min ||X_S c - r||^2, lo <= c <= hi`` equals
``min ||R c - z||^2`` with ``R^T R = X_S^T X_S`` and ``R^T z = X_S^T r``, up to the constant
``r^T r - z^T z``. This is what makes a beam search over term subsets (instead of greedy forward selection,
which a strong but wrong first term can lead astray) affordable.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import lsq_linear

__all__ = ["SubsetLS"]


class SubsetLS:
    """Sufficient statistics of ``r ~ X c`` for fitting subsets of column blocks.

    Parameters
    ----------
    X : shape=(n, p), all columns of all terms (units of the residual per unit parameter).
    r : shape=(n,), the residual to explain [mm].
    blocks : list of index arrays into the columns, one per term.
    lower, upper : shape=(p,), bounds of each parameter.
    folds : shape=(n,) int labels for leave-one-fold-out cross-validation, or None.
    """

    def __init__(self, X, r, blocks, lower, upper, folds=None):
        self.X = np.asarray(X, float)
        self.r = np.asarray(r, float)
        self.norms = np.maximum(np.linalg.norm(self.X, axis=0), 1e-300)
        Xs = self.X / self.norms
        self.blocks = [np.asarray(b, int) for b in blocks]
        self.lower = np.asarray(lower, float) * self.norms
        self.upper = np.asarray(upper, float) * self.norms
        self.G = Xs.T @ Xs
        self.b = Xs.T @ self.r
        self.rr = float(self.r @ self.r)
        self.folds = []
        if folds is not None:
            for f in np.unique(folds):
                m = folds == f
                Xf = Xs[m]
                self.folds.append((Xf.T @ Xf, Xf.T @ self.r[m], float(self.r[m] @ self.r[m])))

    def columns(self, terms) -> np.ndarray:
        return np.concatenate([self.blocks[t] for t in terms]) if terms else np.zeros(0, int)

    def _solve(self, cols, G, b, rr):
        if cols.size == 0:
            return np.zeros(0), rr
        Gs = G[np.ix_(cols, cols)]
        ridge = 1e-12 * max(np.trace(Gs), 1e-300)
        R = np.linalg.cholesky(Gs + ridge * np.eye(cols.size)).T
        z = np.linalg.solve(R.T, b[cols])
        res = lsq_linear(R, z, bounds=(self.lower[cols], self.upper[cols]), method="bvls")
        c = res.x
        rss = rr - 2.0 * c @ b[cols] + c @ Gs @ c
        return c, max(float(rss), 0.0)

    def fit(self, terms) -> tuple[np.ndarray, float]:
        """Bounded fit of the terms (indices into ``blocks``): (parameters in natural units, rss)."""
        cols = self.columns(terms)
        c, rss = self._solve(cols, self.G, self.b, self.rr)
        return c / self.norms[cols], rss

    def cv_error(self, terms) -> float:
        """Leave-one-fold-out prediction error (sum of squares over the held-out folds); NaN with < 2 folds."""
        if len(self.folds) < 2:
            return float("nan")
        cols = self.columns(terms)
        total = 0.0
        for Gf, bf, rrf in self.folds:
            c, _ = self._solve(cols, self.G - Gf, self.b - bf, self.rr - rrf)
            if cols.size:
                total += rrf - 2.0 * c @ bf[cols] + c @ Gf[np.ix_(cols, cols)] @ c
            else:
                total += rrf
        return float(total)

    def contribution(self, terms, coef) -> list[np.ndarray]:
        """The fitted change of every sample made by each term: list of shape=(n,)."""
        out, k = [], 0
        for t in terms:
            cols = self.blocks[t]
            out.append(self.X[:, cols] @ coef[k:k + cols.size])
            k += cols.size
        return out

    def residual(self, terms, coef) -> np.ndarray:
        cols = self.columns(terms)
        return self.r - (self.X[:, cols] @ coef if cols.size else 0.0)
