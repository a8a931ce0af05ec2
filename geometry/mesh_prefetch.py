"""Mesh one design in the background while the caller does other work (imports, set-up).

``rodlab fea --model solid`` knows which mesh it will need before it has loaded the solver (scikit-fem, scipy's
sparse linear algebra, PARDISO: ~0.15 s): :class:`MeshPrefetch` starts the mesher then, in a thread, and hands the
mesh over when the solid model asks for it; the mesh is the same as meshing in the foreground. Measured
(alternated, 2026-11-27, rod 1#): a rerun, whose mesher computes the cache key (the sources' digest and the
packages' versions) and unpickles the mesh while the solver imports, median 0.87-0.89 s against 1.09 s without
(8 rounds); a first run, which meshes, gains nothing (1.66 s against 1.60 s, 5 rounds): gmsh's Python layer and
OpenCASCADE's parallel booleans compete with the imports for the GIL and the two cores.

With ``topology=True`` the mesher is also asked for the straight mesh's tetrahedra (``on_topology``, see
:func:`geometry.mesh_rod`), which :meth:`MeshPrefetch.linear_topology` hands over before the mesh is finished: the
solid model makes its assembly plan from them while gmsh curves the elements (a first run of rod 1# ~0.15 s less).
"""
from __future__ import annotations

import logging
import threading

from rodlab.core.design import RodDesign
from rodlab.core.fem_mesh import LinearTopology, RodMesh

__all__ = ["MeshPrefetch"]

log = logging.getLogger(__name__)


class MeshPrefetch:
    """A mesher (:class:`~fea.compute.Mesher`) that starts ``mesher(design, **kw)`` at once in a background thread.

    The first call with that design and those keywords waits for it and returns its mesh, or raises its error;
    any other call meshes in the foreground with ``mesher``. ``topology=True``: the mesher (``mesh_rod`` or a
    :class:`~geometry.mesh_cache.MeshCache` of it) is given ``on_topology``, for :meth:`linear_topology`.
    ``hits``, ``misses`` and ``folder`` are the wrapped mesher's (a :class:`~geometry.mesh_cache.MeshCache`), when
    it has them.
    """

    def __init__(self, mesher, design: RodDesign, topology: bool = False, **kw) -> None:
        self.mesher = mesher
        self._design = design
        self._kw = dict(kw)
        self._done = threading.Event()
        self._topology_ready = threading.Event()
        self._topology: LinearTopology | None = None
        self._mesh: RodMesh | None = None
        self._error: BaseException | None = None
        self._pending = True
        extra = {"on_topology": self._put_topology} if topology else {}
        # a daemon: a command that stops with an error before it needs the mesh does not wait for it
        threading.Thread(target=self._run, args=(extra,), name=f"mesh {design.name}", daemon=True).start()

    def _run(self, extra: dict) -> None:
        try:
            self._mesh = self.mesher(self._design, **self._kw, **extra)
        except BaseException as e:  # handed to the caller, raised there
            self._error = e
        finally:
            self._done.set()
            self._topology_ready.set()

    def _put_topology(self, topology: LinearTopology) -> None:
        self._topology = topology
        self._topology_ready.set()

    def _is_pending(self, design: RodDesign, kw: dict) -> bool:
        return self._pending and kw == self._kw and (design is self._design or design == self._design)

    def linear_topology(self, design: RodDesign, **kw) -> LinearTopology | None:
        """The straight tetrahedra of the mesh being made for ``design`` with ``kw``, as soon as the mesher has them;
        None when it has none to give (a mesh from the cache, an order-1 mesh, no ``topology``, an error: the
        mesh's own call then says which), or when ``design`` and ``kw`` are not what is being meshed."""
        if not self._is_pending(design, kw):
            return None
        self._topology_ready.wait()
        return self._topology

    def __call__(self, design: RodDesign, **kw) -> RodMesh:
        if self._is_pending(design, kw):
            self._pending = False
            self._done.wait()
            if self._error is not None:
                raise self._error
            log.debug("mesh of %s from the background", design.name)
            mesh, self._mesh = self._mesh, None
            return mesh
        return self.mesher(design, **kw)

    @property
    def hits(self) -> int:
        return getattr(self.mesher, "hits", 0)

    @property
    def misses(self) -> int:
        return getattr(self.mesher, "misses", 0)

    @property
    def folder(self):
        return getattr(self.mesher, "folder", None)
