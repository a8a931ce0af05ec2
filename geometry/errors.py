"""Exceptions of the geometry package."""
from __future__ import annotations

from rodlab.core.errors import DesignError

__all__ = ["GeometryError"]


class GeometryError(DesignError):
    """A design the CAD or the mesher cannot build; the message names the part and the dimension to change."""
