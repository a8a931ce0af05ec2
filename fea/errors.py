"""Exceptions of the fea package."""
from __future__ import annotations

from rodlab.core.errors import LocatedError

__all__ = ["FeaError"]


class FeaError(LocatedError):
    """An analysis that cannot be run or trusted (names the parameter and the fix)."""
