"""Exceptions of the calibrate package."""
from __future__ import annotations

from rodlab.core.errors import LocatedError

__all__ = ["CalibrationError"]


class CalibrationError(LocatedError):
    """A campaign, robot file or calibration that cannot be used or trusted (says what and why)."""
