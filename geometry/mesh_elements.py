"""The tetrahedra of gmsh's mesh of a rod, read part by part: the finished mesh's (for :func:`geometry.mesh_rod`)
and the straight mesh's, in the finished mesh's vertex numbering (:class:`~rodlab.core.fem_mesh.LinearTopology`,
handed to the solver before gmsh curves the elements)."""
from __future__ import annotations

import numpy as np

from rodlab.core.fem_mesh import LinearTopology

from .errors import GeometryError

__all__ = ["elements", "linear_topology"]


def elements(solids: dict, part_vols: dict, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The tetrahedra of the generated mesh: (connectivity in gmsh node tags, shape=(ne, 4 or 10); the part
    index of each; its minimum scaled inverse condition number)."""
    import gmsh

    conn, part_idx, etags = _tetrahedra(solids, part_vols, order)
    return conn, part_idx, gmsh.model.mesh.getElementQualities(etags, "minSICN")


def _tetrahedra(solids: dict, part_vols: dict, order: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(connectivity in gmsh node tags, shape=(ne, 4 or 10); part index of each; element tags), part by part and
    volume by volume: the element order of the mesh."""
    import gmsh

    etype = 11 if order == 2 else 4
    conn, part_idx, etags = [], [], []
    for i, part in enumerate(solids):
        for v in sorted(set(part_vols[part])):
            types, tags, nodes = gmsh.model.mesh.getElements(3, v)
            for ty, tg, nd in zip(types, tags, nodes):
                if ty != etype:
                    raise GeometryError(f"unexpected gmsh element type {ty} in {part}")
                conn.append(nd.reshape(len(tg), -1))
                part_idx.append(np.full(len(tg), i))
                etags.append(tg)
    return np.concatenate(conn), np.concatenate(part_idx), np.concatenate(etags)


def linear_topology(solids: dict, part_vols: dict) -> LinearTopology:
    """The straight mesh's tetrahedra in the vertex numbering the finished mesh will have (``geometry.mesh._to_skfem``
    numbers the nodes in gmsh's node order, scikit-fem then the vertices in theirs; gmsh's order-2 elevation adds
    the edge nodes and keeps the vertices' order)."""
    import gmsh

    node_tags = gmsh.model.mesh.getNodes(returnParametricCoord=False)[0].astype(np.int64)
    conn = _tetrahedra(solids, part_vols, 1)[0].astype(np.int64)
    position = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
    position[node_tags] = np.arange(node_tags.size)
    used, t = np.unique(position[conn], return_inverse=True)
    return LinearTopology(np.ascontiguousarray(t.reshape(conn.shape).T, dtype=np.int64), int(used.size))
