"""scikit-fem bases whose curved-element mapping is inverted once per set of points.

scikit-fem's :class:`~skfem.assembly.CellBasis` asks the mapping for the inverse Jacobian once per local basis
function (``ElementH1.gbasis``): ten times for a P2 tetrahedron, each time forming the 3x3 cofactors of the
isoparametric Jacobian over every element and point again (the Jacobian itself is cached by scikit-fem).
:class:`InverseOnceMapping` keeps the last inverse and returns it while the same points are asked for; the values
are scikit-fem's own. Imported only where a basis is built (scikit-fem loads with it).
"""
from __future__ import annotations

import numpy as np
from skfem import Basis
from skfem.mapping import MappingIsoparametric

__all__ = ["InverseOnceMapping", "lagrange_basis"]


class InverseOnceMapping(MappingIsoparametric):
    """:class:`skfem.mapping.MappingIsoparametric` whose ``invDF`` is kept for the last points asked for (the
    same ``X`` and ``tind`` objects: a basis asks with its own arrays, once per local function)."""

    _last: tuple | None = None

    def invDF(self, X, tind=None):
        last = self._last
        if last is not None and last[0] is X and last[1] is tind:
            return last[2]
        out = super().invDF(X, tind)
        self._last = (X, tind, out)
        return out


def lagrange_basis(mesh, elem, intorder: int | None = None, quadrature: tuple | None = None,
                   doflocs: bool = True) -> Basis:
    """``skfem.Basis(mesh, elem, ...)``, the same basis, with a curved mesh's inverse Jacobian formed once
    instead of once per local function (:class:`InverseOnceMapping`; an affine mesh keeps its own mapping).
    ``quadrature``: (points, weights) on the reference element, shape=(3, nq) and (nq,); ``doflocs=False`` skips
    the global DOF locations (``basis.doflocs``) a caller does not use."""
    mapping = mesh.mapping() if mesh.affine else InverseOnceMapping(mesh, mesh.elem(), mesh.bndelem)
    if quadrature is not None:
        quadrature = (np.asarray(quadrature[0], dtype=float), np.asarray(quadrature[1], dtype=float))
    return Basis(mesh, elem, mapping=mapping, intorder=intorder, quadrature=quadrature, disable_doflocs=not doflocs)
