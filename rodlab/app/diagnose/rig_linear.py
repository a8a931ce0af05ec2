"""The linear compliance a recording measures, fitted freely (the paper's r_mn of Eq. 20, entry by entry).

A rig diagnosis that is not told the simulation is exact separates what no linear compliance can produce
(friction, tare, creep, hysteresis, non-linearity, crosstalk, drift, effects outside the library) from the
linear compliance itself: the C_F entries a planar rod has (c11, c13 = c31, c22, c33; Maxwell-Betti ties c13 and
c31) are free nuisance parameters of the reading model, projected out of the residual and of every hypothesis
together with the gauge zeros (Frisch-Waugh), so a simulation that is off in form can neither hide nor fake an
effect. The fitted entries and their covariance are then judged against the simulation's envelope
(:mod:`.rig_form`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.core.sensitivity import STRUCTURAL_ENTRIES
from rodlab.stiffness_rig.samples import RigSamples

from .rig_select import demean

__all__ = ["LinearPart", "measured_entries", "linear_columns", "Projector", "fit_linear"]


@dataclass(frozen=True)
class LinearPart:
    """The freely fitted linear compliance of a recording.

    entries : the fitted C_F entries (m, n), m <= n; C : their values [mm/N], shape=(k,); cov : their covariance
    [(mm/N)^2], shape=(k, k); C_F : the full matrix [mm/N], shape=(3, 3): fitted entries (symmetric), the
    simulation's elsewhere
    """

    entries: tuple
    C: np.ndarray
    cov: np.ndarray
    C_F: np.ndarray

    def __post_init__(self) -> None:
        k = len(self.entries)
        if np.shape(self.C) != (k,) or np.shape(self.cov) != (k, k) or np.shape(self.C_F) != (3, 3):
            raise ValueError(f"LinearPart: C ({k},), cov ({k}, {k}), C_F (3, 3) expected, got {np.shape(self.C)}, "
                             f"{np.shape(self.cov)}, {np.shape(self.C_F)}")

    def sd(self) -> np.ndarray:
        return np.sqrt(np.clip(np.diag(self.cov), 0, None))


def measured_entries(data: RigSamples, C_sim: np.ndarray) -> tuple:
    """The structural C_F entries (:data:`~rodlab.core.sensitivity.STRUCTURAL_ENTRIES`, non-zero in the simulation or
    on the diagonal) that some gauge measures under some load axis (either way round: Maxwell-Betti)."""
    scale = float(np.abs(C_sim).max())
    pairs = set(zip(data.comp.tolist(), data.axis.tolist()))
    out = []
    for m, n in STRUCTURAL_ENTRIES:
        if m != n and abs(C_sim[m, n]) < 1e-6 * scale:
            continue
        if (m, n) in pairs or (n, m) in pairs:
            out.append((m, n))
    return tuple(out)


def linear_columns(data: RigSamples, entries) -> np.ndarray:
    """Reading per unit of each entry: the signed load on the readings of that (gauge, load axis) pair and its
    mirror [N], shape=(n, k)."""
    cols = np.zeros((data.n, len(entries)))
    for j, (m, n) in enumerate(entries):
        hit = ((data.comp == m) & (data.axis == n)) | ((data.comp == n) & (data.axis == m))
        cols[hit, j] = data.F[hit]
    return cols


class Projector:
    """Residualise columns on the nuisance: each series' gauge zero (group means) and the free linear entries."""

    def __init__(self, groups: np.ndarray, L: np.ndarray) -> None:
        self.groups = groups
        self.Ld = demean(L, groups)
        self.pinv = np.linalg.pinv(self.Ld)

    def __call__(self, A: np.ndarray) -> np.ndarray:
        Ad = demean(A, self.groups)
        return Ad - self.Ld @ (self.pinv @ Ad)


def fit_linear(data: RigSamples, entries, L: np.ndarray, y_minus_effects: np.ndarray, sigma: float,
               C_sim: np.ndarray, inflation: float = 1.0, effects: np.ndarray | None = None) -> LinearPart:
    """The entries fitted to the readings less the chosen effects' fitted change (gauge zeros projected out), with
    the covariance of a joint fit with the effects' columns ``effects`` (gauge zeros removed; shape=(n, p)):
    ``sigma^2 [(L, X)^T (L, X)]^-1``'s linear block, times ``inflation`` (the lack of fit's reduced chi-square,
    at least 1). An effect that varies with the load as the compliance does (fast creep, hysteresis) widens it."""
    groups = data.zero_groups
    Ld = demean(L, groups)
    yd = demean(y_minus_effects, groups)
    coef, *_ = np.linalg.lstsq(Ld, yd, rcond=None)
    M = Ld if effects is None or np.size(effects) == 0 else np.column_stack([Ld, effects])
    cov = sigma ** 2 * max(inflation, 1.0) * np.linalg.pinv(M.T @ M)[:Ld.shape[1], :Ld.shape[1]]
    C_F = np.array(C_sim, float).copy()
    for (m, n), c in zip(entries, coef):
        C_F[m, n] = C_F[n, m] = c
    return LinearPart(tuple(entries), coef, cov, C_F)
