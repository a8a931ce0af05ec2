"""The acceptance rule both diagnosers apply to a hypothesis (or a set of them): one place for the thresholds.

A larger model replaces the current one only if

1. it is significant: delta BIC <= -:data:`DBIC_MIN` (with the known noise, so the likelihood ratio is the
   drop in chi-square and the penalty ``k ln n``, or a stricter one for a per-point term) and the
   likelihood-ratio test gives p <= :data:`P_MAX`;
2. it predicts left-out data better (:func:`cv_improves`: leave-one-repeat-out on the rig, leave-one-point-out
   in a campaign);
3. it is above the detection limit, which each diagnoser sets for its data (rig: ``rig_select.PTP_MIN`` noise
   SDs peak to peak in a series; campaign: 2 device-noise SDs at some point).

Both diagnosers run the same selection routine (:mod:`.search`) and apply this rule at every step; what differs
is the search space, because their data differ: the rig (many readings, repeats, physical bounds on every
parameter) keeps a beam of subsets of its library from one Gram matrix (:mod:`.rig_select`); a campaign (a few
dozen points, no repeats, scatter known only up to a Birge ratio) extends its current model on whitened
residuals (:mod:`.campaign`). Both report the same evidence keys (:meth:`Evidence.to_dict`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .chi2 import chi2_sf

__all__ = ["DBIC_MIN", "P_MAX", "Evidence", "evidence", "bic_penalty", "cv_improves", "weakest_term"]

#: delta BIC a model must gain to be accepted ("very strong" evidence on Kass & Raftery's scale)
DBIC_MIN = 10.0
#: largest p-value of the likelihood-ratio test for an accepted model
P_MAX = 1e-3


@dataclass(frozen=True)
class Evidence:
    """The significance of adding ``dof`` parameters.

    lr : likelihood-ratio chi-square, the drop in the (noise-normalised) residual sum of squares [-]
    dof : parameters added (>= 1)
    dbic : delta BIC = -lr + penalty (negative: the larger model is better) [-]
    p : P(chi-square with ``dof`` degrees of freedom > lr)
    """

    lr: float
    dof: int
    dbic: float
    p: float

    @property
    def significant(self) -> bool:
        """Delta BIC and the likelihood-ratio test both pass."""
        return self.dbic <= -DBIC_MIN and self.p <= P_MAX

    def to_dict(self) -> dict:
        """The evidence keys of a diagnosis finding."""
        return {"delta_bic": float(self.dbic), "lr_chi2": float(self.lr), "lr_p": float(self.p)}


def bic_penalty(k: int, n: int) -> float:
    """BIC's penalty of ``k`` parameters fitted to ``n`` readings."""
    return k * float(np.log(n))


def evidence(lr: float, dof: int, penalty: float) -> Evidence:
    """The :class:`Evidence` of a likelihood ratio ``lr`` for ``dof`` added parameters costing ``penalty``
    (:func:`bic_penalty`, or more for a term that can absorb one point)."""
    dof = max(int(dof), 1)
    return Evidence(float(lr), dof, float(-lr + penalty), chi2_sf(max(float(lr), 0.0), dof))


def cv_improves(before: float, after: float) -> bool:
    """The cross-validated prediction error drops (always True without folds: ``before`` is NaN)."""
    return not np.isfinite(before) or after < before


def weakest_term(terms, lr_without, npar, n: int):
    """The drop-one test of both diagnosers: among ``terms`` of the final model, the one whose removal costs the
    smallest likelihood ratio ``lr_without(term)`` while that removal is not significant (BIC penalty of its
    ``npar(term)`` parameters over ``n`` readings); None when every term is needed."""
    weakest = None
    for t in terms:
        lr = lr_without(t)
        if not evidence(lr, npar(t), bic_penalty(npar(t), n)).significant and (weakest is None or lr < weakest[1]):
            weakest = (t, lr)
    return None if weakest is None else weakest[0]

