"""The error budget of a predicted calibration: what each source adds to the mean-square validation error.

Both predictors (Monte Carlo, :mod:`calibrate.predict`; linear, :mod:`calibrate.predict_linear`) calibrate the
same campaign up to four ways and validate each:

- with the method's compliance file: mean square ``ms``;
- with the true rod's compliance (what a perfect compensation would give): ``ms_true``;
- with the true rod's compliance on the campaign without the rod's slip (:mod:`calibrate.rod_slip`; only when
  the priors have one): ``ms_true_no_slip``;
- the true robot's own model, no identification: ``ms_clean`` (the validation instrument's noise and the
  robot's own unmodelled error).

The differences are the shares (:class:`BudgetShares`): ``deflection = ms - ms_true`` (what the compensation
leaves of the rod's elastic deflection), ``slip = ms_true - ms_true_no_slip`` (the rod's non-repeatable
deflection: no compensation removes it), ``identification = ms_true_no_slip - ms_clean`` (the campaign's noise
and fixture uncertainty through the observability, the priors' pull on weak parameters) and ``noise =
ms_clean``. A difference the sampling makes negative counts 0; the shares are normalised to sum 1.
:class:`AccuracySummary` is what a predictor says of one method: its errors and their budget.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rodlab.core.enums import Method

__all__ = ["BudgetShares", "budget_shares", "AccuracySummary"]


@dataclass(frozen=True)
class BudgetShares:
    """Shares of the mean-square validation error [-] (sum 1; see the module docstring): ``deflection`` left after
    compensation, ``identification`` (noise through observability), validation ``noise``, and the rod's ``slip``
    (its non-repeatable deflection through the identification; 0 without one)."""

    deflection: float
    identification: float
    noise: float
    slip: float = 0.0

    def to_dict(self) -> dict:
        return {"deflection": self.deflection, "identification": self.identification, "noise": self.noise,
                "slip": self.slip}

    @classmethod
    def from_dict(cls, d: dict) -> "BudgetShares":
        """From :meth:`to_dict` (a ``slip`` missing, as written before it was split off: 0; None: NaN)."""
        def f(key, default=float("nan")):
            v = d.get(key, default)
            return float("nan") if v is None else float(v)
        return cls(f("deflection"), f("identification"), f("noise"), f("slip", 0.0))


def budget_shares(ms: float, ms_true: float, ms_clean: float,
                  ms_true_no_slip: float = float("nan")) -> BudgetShares:
    """The shares from the four mean squares [mm^2] (module docstring); ``ms_true_no_slip`` NaN: no slip share (the
    slip, if any, counted as identification). All NaN when ``ms_true`` is not finite or ``ms`` <= 0."""
    if not math.isfinite(ms_true) or ms <= 0:
        return BudgetShares(float("nan"), float("nan"), float("nan"), float("nan"))
    has_slip = math.isfinite(ms_true_no_slip)
    ms_ns = ms_true_no_slip if has_slip else ms_true
    parts = np.maximum([ms - ms_true, ms_ns - ms_clean, ms_clean, ms_true - ms_ns], 0.0)
    parts = parts / max(parts.sum(), 1e-300)
    return BudgetShares(*(float(p) for p in parts))


@dataclass(frozen=True)
class AccuracySummary:
    """Predicted validation errors of one method over the replicates [mm].

    mean_mm, max_mm, median_mm : averages over replicates of each campaign's mean / max / median error;
    mean_p05_mm, mean_p95_mm : the 5 % and 95 % points of the campaigns' mean error (the 90 % band);
    rms_mm : root of the average mean-square error; budget : its shares; replicates, failed : counts
    """

    method: Method
    mean_mm: float
    max_mm: float
    median_mm: float
    mean_p05_mm: float
    mean_p95_mm: float
    rms_mm: float
    budget: BudgetShares
    replicates: int
    failed: int = 0
    means_mm: tuple = field(default=(), repr=False)
