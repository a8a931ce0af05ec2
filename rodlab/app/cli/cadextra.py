"""The CAD extra (build123d, gmsh) for the commands that need it."""
from __future__ import annotations

import importlib.util

from ...core.errors import RodlabError

__all__ = ["require_cad", "require_mesher"]


def require_cad():
    """Import the geometry package, or explain how to install the CAD extra."""
    try:
        import gmsh  # noqa: F401
        import rodlab.geometry as geometry
        from rodlab.geometry.cadlib import build123d
        build123d()                         # imported here (without scikit-learn: geometry.cadlib), not later
    except ImportError as e:
        raise RodlabError(f"this command needs the CAD extra ({e.name} is missing): pip install 'rodlab[cad]'") from e
    return geometry


def require_mesher():
    """The geometry package for meshing only (gmsh builds the parts itself: build123d is not imported), or
    explain how to install the CAD extra."""
    if importlib.util.find_spec("gmsh") is None:          # found, not imported: a cached mesh never needs it
        raise RodlabError("this command needs the CAD extra (gmsh is missing): pip install 'rodlab[cad]'")
    return importlib.import_module("rodlab.geometry")     # its modules load on first use: nothing to fail here
