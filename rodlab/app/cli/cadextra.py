"""The CAD extra (build123d, gmsh) for the commands that need it, and the design argument of ``cad`` and ``mesh``."""
from __future__ import annotations

from ...errors import RodlabError

__all__ = ["require_cad", "require_mesher", "DESIGN_HELP"]

#: help of the design argument of cad and mesh
DESIGN_HELP = "a *.rod.toml file, or a built-in design: rod1 .. rod6"


def require_cad():
    """Import the geometry package, or explain how to install the CAD extra."""
    try:
        import build123d  # noqa: F401
        import gmsh  # noqa: F401
        import rodlab.geometry as geometry
    except ImportError as e:
        raise RodlabError(f"this command needs the CAD extra ({e.name} is missing): pip install 'rodlab[cad]'") from e
    return geometry


def require_mesher():
    """The geometry package for meshing only (gmsh builds the parts itself: build123d is not imported), or
    explain how to install the CAD extra."""
    try:
        import gmsh  # noqa: F401
        import rodlab.geometry as geometry
    except ImportError as e:
        raise RodlabError(f"this command needs the CAD extra ({e.name} is missing): pip install 'rodlab[cad]'") from e
    return geometry
