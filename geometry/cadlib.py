"""build123d, imported once, without scikit-learn until someone needs it.

build123d's ``__init__`` imports ``build123d.brep_from_stl``, which imports scikit-learn's ``DBSCAN`` at module
level for one function, ``detect_primitives`` (STL triangles -> B-rep primitives), that rodlab never calls; that
import (scikit-learn, scipy.stats) is ~1.1-1.3 s of build123d's ~3.5 s on the 2-core machines measured
(``rodlab cad``, the demo's CAD stage, every CAD view). :func:`build123d` imports build123d with
``sklearn.cluster`` answered by a stand-in whose ``DBSCAN`` imports the real one when called, so
``detect_primitives`` works as before; the stand-in is removed from ``sys.modules`` right after, so an import
of ``sklearn.cluster`` anywhere else gets scikit-learn itself. Where scikit-learn is already imported, nothing
is stood in.
"""
from __future__ import annotations

import importlib
import sys
import types

__all__ = ["build123d", "STAND_IN"]

#: the module name answered by the stand-in while build123d is imported
STAND_IN = "sklearn.cluster"


def DBSCAN(*args, **kwargs):
    """scikit-learn's ``sklearn.cluster.DBSCAN(*args, **kwargs)``, imported on this first use."""
    return importlib.import_module(STAND_IN).DBSCAN(*args, **kwargs)


def build123d() -> types.ModuleType:
    """The build123d module (imported here on first use; see the module docstring)."""
    if "build123d" in sys.modules or STAND_IN in sys.modules:
        return importlib.import_module("build123d")
    stand_in = types.ModuleType(STAND_IN, "rodlab's stand-in while build123d imports (geometry.cadlib)")
    stand_in.DBSCAN = DBSCAN
    sys.modules[STAND_IN] = stand_in
    try:
        return importlib.import_module("build123d")
    finally:
        if sys.modules.get(STAND_IN) is stand_in:
            del sys.modules[STAND_IN]
