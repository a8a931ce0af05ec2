"""geometry: the rod as a build123d CAD assembly (STEP/STL/PNG, mass properties) and a gmsh FEA mesh.

Needs the ``cad`` extra (build123d, gmsh); both are imported inside the functions that use them. The
mesh is returned as the core type :class:`rodlab.core.fem_mesh.RodMesh`, which ``fea`` consumes.
"""
from .assembly import RodCad, build_cad
from .errors import GeometryError
from .mesh import default_size_mm, feature_circles, mesh_rod
from .mesh_cache import MeshCache
from .parts import PART_COLOURS, part_solids
from .render import render_views

__all__ = ["RodCad", "build_cad", "GeometryError", "mesh_rod", "MeshCache", "default_size_mm", "feature_circles",
           "PART_COLOURS", "part_solids", "render_views"]
