"""Exceptions of the stiffness_rig package."""
from __future__ import annotations

from rodlab.core.errors import LocatedError

__all__ = ["RigError", "DeviceError", "NoLoadResponse"]


class RigError(LocatedError):
    """A recording, profile or plan that cannot be used (names the file, line and column)."""


class DeviceError(RigError):
    """An instrument that does not answer or answers garbage beyond the retry policy."""


class NoLoadResponse(RigError):
    """A load axis does not deflect the rod along itself: the gauges or the loading, not the rod."""
