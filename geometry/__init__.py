"""geometry: the rod as a build123d CAD assembly (STEP/STL/PNG, mass properties) and a gmsh FEA mesh.

Needs the ``cad`` extra (build123d, gmsh); both are imported inside the functions that use them.
"""
from .assembly import RodCad, build_cad, part_material
from .errors import GeometryError
from .mesh import RodMesh, default_size_mm, mesh_rod
from .parts import PART_COLOURS, part_solids
from .render import render_views

__all__ = ["RodCad", "build_cad", "part_material", "GeometryError", "RodMesh", "mesh_rod", "default_size_mm",
           "PART_COLOURS", "part_solids", "render_views"]
