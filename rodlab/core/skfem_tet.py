"""scikit-fem's tetrahedral meshes with their edges and facets found from integer keys.

scikit-fem finds a mesh's edges and facets with ``np.unique(..., axis=1)`` on the sorted node pairs and triples,
which sorts them as structured records: on rod 1#'s half mesh (7932 curved tetrahedra) 0.03 s for the edges and
0.02 s for the facets, made once for the straight tetrahedra beside the mesher (:mod:`fea.ahead`) and once more in
the mesher's thread for the finished mesh, on the way of a first ``rodlab fea --model solid``. A pair or triple of
sorted node numbers is one integer key (``a n^2 + b n + c``), and one ``np.unique`` of the keys gives the same
entities, in the same (lexicographic) order with the same first occurrences and inverse: :class:`MeshTet1Keyed` and
:class:`MeshTet2Keyed` are scikit-fem's meshes with that :meth:`build_entities`, nothing else changed
(``tests/test_mesh_topology.py`` checks the entities equal). This module imports scikit-fem: import it where a mesh
is made.
"""
from __future__ import annotations

import numpy as np
from skfem import MeshTet1, MeshTet2

__all__ = ["MeshTet1Keyed", "MeshTet2Keyed", "keyed_entities"]


def keyed_entities(t: np.ndarray, indices, sort: bool = True):
    """scikit-fem's ``Mesh.build_entities``: the entities (node tuples ``indices`` of each element of ``t``,
    shape=(nodes, ne)), sorted and unique, shape=(k, n_entities), and each element's entity numbers,
    shape=(len(indices), ne); ``sort`` False: each entity's nodes as its first occurrence lists them."""
    if indices is None:
        return None, None
    indexing = np.hstack(tuple(t[ix] for ix in indices))
    ordered = np.sort(indexing, axis=0).astype(np.int64)
    n = int(ordered.max()) + 1 if ordered.size else 1
    if float(n) ** ordered.shape[0] >= 2.0 ** 62:             # keys would overflow: scikit-fem's own way
        return MeshTet1.build_entities(t, indices, sort)
    keys = ordered[0].copy()
    for row in ordered[1:]:
        keys *= n
        keys += row
    _, first, inverse = np.unique(keys, return_index=True, return_inverse=True)
    mapping = inverse.reshape((len(indices), t.shape[1]))
    entities = ordered[:, first] if sort else indexing[:, first]
    return np.ascontiguousarray(entities.astype(indexing.dtype, copy=False)), mapping


class MeshTet1Keyed(MeshTet1):
    """:class:`skfem.MeshTet1` whose edges and facets come from :func:`keyed_entities`."""

    build_entities = staticmethod(keyed_entities)


class MeshTet2Keyed(MeshTet2):
    """:class:`skfem.MeshTet2` whose edges and facets come from :func:`keyed_entities`."""

    build_entities = staticmethod(keyed_entities)
