"""geometry: the rod as a build123d CAD assembly (STEP/STL/PNG, mass properties) and a gmsh FEA mesh.

Needs the ``cad`` extra (build123d, gmsh); both are imported inside the functions that use them. The
mesh is returned as the core type :class:`rodlab.core.fem_mesh.RodMesh`, which ``fea`` consumes.

The names below load their module on first use (PEP 562): ``rodlab fea`` on a cached mesh does not import the
renderer (~10 ms of its start-up).
"""
from __future__ import annotations

from rodlab.core.lazy import lazy_exports

#: each public name and the module it comes from
_EXPORTS = {
    "RodCad": "assembly", "build_cad": "assembly",
    "GeometryError": "errors",
    "mesh_rod": "mesh", "default_size_mm": "mesh_size", "feature_circles": "mesh",
    "MeshCache": "mesh_cache", "MeshPrefetch": "mesh_prefetch",
    "PART_COLOURS": "parts", "part_solids": "parts",
    "render_views": "render",
}

__all__ = list(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
