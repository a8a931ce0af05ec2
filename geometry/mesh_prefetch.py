"""Mesh one design in the background while the caller does other work (imports, set-up).

``rodlab fea --model solid`` knows which mesh it will need before it has loaded the solver (scikit-fem, scipy's
sparse linear algebra, PARDISO: ~0.15 s): :class:`MeshPrefetch` starts the mesher then, in a thread, and hands the
mesh over when the solid model asks for it; the mesh is the same as meshing in the foreground. Measured
(alternated, 2026-11-27, rod 1#): a rerun, whose mesher computes the cache key (the sources' digest and the
packages' versions) and unpickles the mesh while the solver imports, median 0.87-0.89 s against 1.09 s without
(8 rounds); a first run, which meshes, gains nothing (1.66 s against 1.60 s, 5 rounds): gmsh's Python layer and
OpenCASCADE's parallel booleans compete with the imports for the GIL and the two cores.
"""
from __future__ import annotations

import logging
import threading

from rodlab.core.design import RodDesign
from rodlab.core.fem_mesh import RodMesh

__all__ = ["MeshPrefetch"]

log = logging.getLogger(__name__)


class MeshPrefetch:
    """A mesher (:class:`~fea.compute.Mesher`) that starts ``mesher(design, **kw)`` at once in a background thread.

    The first call with that design and those keywords waits for it and returns its mesh, or raises its error;
    any other call meshes in the foreground with ``mesher``. ``hits``, ``misses`` and ``folder`` are the wrapped
    mesher's (a :class:`~geometry.mesh_cache.MeshCache`), when it has them.
    """

    def __init__(self, mesher, design: RodDesign, **kw) -> None:
        self.mesher = mesher
        self._design = design
        self._kw = dict(kw)
        self._done = threading.Event()
        self._mesh: RodMesh | None = None
        self._error: BaseException | None = None
        self._pending = True
        # a daemon: a command that stops with an error before it needs the mesh does not wait for it
        threading.Thread(target=self._run, name=f"mesh {design.name}", daemon=True).start()

    def _run(self) -> None:
        try:
            self._mesh = self.mesher(self._design, **self._kw)
        except BaseException as e:  # handed to the caller, raised there
            self._error = e
        finally:
            self._done.set()

    def __call__(self, design: RodDesign, **kw) -> RodMesh:
        if self._pending and kw == self._kw and (design is self._design or design == self._design):
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
