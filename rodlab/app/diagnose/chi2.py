"""The chi-square distribution functions the diagnosers use, from scipy.special (what scipy.stats.chi2 calls
underneath) so that importing the diagnosis does not import scipy.stats (~0.9 s)."""
from __future__ import annotations

from scipy.special import chdtrc, chdtri

__all__ = ["chi2_sf", "chi2_median"]


def chi2_sf(x: float, df: float) -> float:
    """P(X > x) for X ~ chi-square with ``df`` degrees of freedom."""
    return float(chdtrc(df, x))


def chi2_median(df: float) -> float:
    """The median of the chi-square distribution with ``df`` degrees of freedom."""
    return float(chdtri(df, 0.5))
