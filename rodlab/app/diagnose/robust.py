"""Robust scale of whitened residuals: how far a gross error (an outlier, one badly clamped position) spreads
through a least-squares fit, and how to keep it from inflating the scatter every other effect is judged by.

A least-squares fit smears a gross error over every residual, so the median of the least-squares residuals
overstates the scatter once a few points are far off. A redescending M-estimator (Tukey's biweight on each
point's residual norm, iteratively reweighted least squares from the least-squares start) gives the
remaining points their own fit: its scale is the scatter of the data without the gross errors, and its
residuals show where those errors sit.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chi2 import chi2_median

__all__ = ["RobustFit", "robust_fit", "median_reduced_chi2"]

#: Tukey biweight tuning constant (the 1-D 95 %-efficiency value), applied to a point's residual norm per
#: coordinate, sqrt(d^2 / 3) / s: a point is set aside beyond 4.685 sigma rms per coordinate (chi-square(3) of
#: 66, p ~ 1e-13) — only gross errors, never the tail of the noise
TUKEY_C = 4.685


@dataclass(frozen=True)
class RobustFit:
    """A robust fit of whitened residuals on the columns of a model.

    weights : shape=(N,), biweight of each point in [0, 1]; residuals : shape=(N, 3), whitened residuals of
    the robust fit; reduced_chi2 : robust reduced chi-square of the points (median, corrected for the fitted
    columns), 1 when the scatter is the noise model's
    """

    weights: np.ndarray
    residuals: np.ndarray
    reduced_chi2: float

    def __post_init__(self) -> None:
        n = self.weights.shape[0]
        if self.residuals.shape != (n, 3):
            raise ValueError(f"residuals must have shape ({n}, 3), got {self.residuals.shape}")


def median_reduced_chi2(e: np.ndarray, n: int, k: int) -> float:
    """Reduced chi-square of whitened residuals ``e`` (n readings, k fitted parameters), robust: the median
    over the points, so isolated outliers or one wrong position cannot hide themselves."""
    per_point = (e.reshape(-1, 3) ** 2).sum(axis=1) * n / max(n - k, 1)
    return float(np.median(per_point)) / float(chi2_median(3))


def robust_fit(A: np.ndarray, r: np.ndarray, iterations: int = 30) -> RobustFit:
    """Tukey-biweight fit of ``r`` (3N,) on the columns of ``A`` (3N, k), one weight per point (3 readings)."""
    n, k = A.shape
    N = n // 3
    w = np.ones(N)
    for _ in range(iterations):
        W = np.repeat(np.sqrt(w), 3)
        coef = np.linalg.lstsq(A * W[:, None], r * W, rcond=None)[0]
        e = (r - A @ coef).reshape(N, 3)
        d2 = (e ** 2).sum(axis=1)
        s2 = max(float(np.median(d2)) / chi2_median(3), 1e-300)
        u = np.sqrt(d2 / s2 / 3.0) / TUKEY_C
        w_new = np.where(u < 1.0, (1.0 - u ** 2) ** 2, 0.0)
        converged = np.allclose(w_new, w, atol=1e-6)
        w = w_new
        if converged:
            break
    return RobustFit(w, e, median_reduced_chi2(e, n, k))
