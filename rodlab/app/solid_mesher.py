"""The mesher the application gives the solid model: already at work in the background.

:func:`solid_mesher` starts meshing the design as the solid model will ask for it (:func:`fea.mesh_request.
solid_mesh_request`) in a thread (:class:`rodlab.geometry.MeshPrefetch`) and has the straight tetrahedra handed
over before gmsh curves them, so that the solid model makes its assembly plan and its solver's analysis meanwhile
(:mod:`fea.ahead`): ``rodlab fea --model solid``, the demo's FEA stage and the study's family calibration use it.
"""
from __future__ import annotations

import importlib

from rodlab.core.design import RodDesign
from rodlab.fea.mesh_request import solid_mesh_request

__all__ = ["solid_mesher"]


def solid_mesher(design: RodDesign, size_mm: float | None = None, symmetry: bool = True, cache: bool = False):
    """``geometry.mesh_rod`` (through the per-user mesh cache with ``cache``), meshing ``design`` at ``size_mm``
    (None: the default) in the background from now on. Raises :class:`~fea.errors.FeaError` for a size the solid
    model refuses, before anything starts."""
    geometry = importlib.import_module("rodlab.geometry")   # its modules load on first use
    request = solid_mesh_request(design, size_mm, symmetry=symmetry)
    mesher = geometry.MeshCache(geometry.mesh_rod) if cache else geometry.mesh_rod
    return geometry.MeshPrefetch(mesher, design, topology=True, **request.kwargs)
