"""A per-user cache of rod meshes: a designer who reruns ``rodlab fea`` on the same design and size skips gmsh.

The key is the SHA-256 of everything the mesh depends on: the design as a ``rodlab.rod`` table (every dimension,
part and material), the mesher's keywords (size, grading, half / whole), the source of the geometry package and
of the core modules it builds from (so that a change to the mesher is never served an old mesh), the versions of
gmsh, scikit-fem and numpy, and :data:`MESH_REVISION`. A hit is the pickled
:class:`~rodlab.core.fem_mesh.RodMesh` (~2 MB for rod 1#'s default half mesh); a file that cannot be read is
meshed again and replaced. Files are written atomically; the folder is pruned to :data:`MAX_BYTES`, oldest first.

Folder: ``$RODLAB_CACHE_DIR/meshes``, else ``$XDG_CACHE_HOME/rodlab/meshes``, else ``~/.cache/rodlab/meshes``;
``RODLAB_CACHE_DIR=off`` (or ``rodlab fea --no-cache``) turns it off. The files are pickles: only a file owned
by the user who runs rodlab is read (another user's file in a shared folder is ignored and meshed anew).
"""
from __future__ import annotations

import hashlib
import json
import logging
import pickle
import sys
from functools import lru_cache
from pathlib import Path

from rodlab.core.cache import cache_subfolder, code_digest, load, store
from rodlab.core.design import RodDesign
from rodlab.core.design_io import design_to_dict
from rodlab.core.fem_mesh import RodMesh

__all__ = ["MeshCache", "MESH_REVISION", "MAX_BYTES", "cache_folder"]

log = logging.getLogger(__name__)

#: raise when the mesh changes for a reason the key cannot see (the sources and versions are in it)
MESH_REVISION = 1
#: the core modules the mesher builds from, besides its own package
_CORE_SOURCES = ("layout.py", "fem_mesh.py", "design.py", "enums.py")
#: the folder's size limit [bytes]
MAX_BYTES = 500_000_000


def cache_folder() -> Path | None:
    """Where meshes are cached (``meshes`` in :func:`rodlab.core.cache.cache_root`), or None when
    ``RODLAB_CACHE_DIR`` is ``off``."""
    return cache_subfolder("meshes")


@lru_cache(maxsize=1)
def _code_and_versions() -> str:
    """The SHA-256 of the geometry package's and the mesher's core modules' sources, and the versions of the
    packages a mesh is made and pickled with."""
    core = Path(sys.modules[RodMesh.__module__].__file__).resolve().parent
    return code_digest(__name__, tuple(core / name for name in _CORE_SOURCES), ("gmsh", "scikit-fem", "numpy"))


def _unpickle(path: Path):
    with open(path, "rb") as f:
        return pickle.load(f)


class MeshCache:
    """A :class:`~fea.compute.Mesher` that remembers: ``MeshCache(mesh_rod)(design, size_mm=..., grading=...,
    half=...)`` returns the cached mesh or meshes, stores and returns it. ``hits`` / ``misses`` count calls.
    ``on_topology`` (:func:`~geometry.mesh.mesh_rod`'s) is not part of the key: it goes to the mesher when it
    meshes, and is not called for a mesh from the cache."""

    def __init__(self, mesher, folder: Path | None | str = "default") -> None:
        self.mesher = mesher
        self.folder = cache_folder() if folder == "default" else (Path(folder) if folder else None)
        self.hits = self.misses = 0

    def key(self, design: RodDesign, **kw) -> str:
        """The SHA-256 naming the mesh of ``design`` with the mesher's keywords ``kw``."""
        text = json.dumps({"design": design_to_dict(design), "mesher": {k: kw[k] for k in sorted(kw)},
                           "code": _code_and_versions(), "revision": MESH_REVISION}, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def __call__(self, design: RodDesign, on_topology=None, **kw) -> RodMesh:
        kw_mesher = kw if on_topology is None else dict(kw, on_topology=on_topology)
        if self.folder is None:
            return self.mesher(design, **kw_mesher)
        path = self.folder / f"{self.key(design, **kw)}.pickle"
        found = self._read(path)
        if found is not None:
            self.hits += 1
            log.info("mesh of %s from the cache (%s)", design.name, path)
            return found
        self.misses += 1
        rm = self.mesher(design, **kw_mesher)
        self._write(path, rm)
        return rm

    def _read(self, path: Path) -> RodMesh | None:
        return load(path, _unpickle, lambda rm: isinstance(rm, RodMesh), "mesh")

    def _write(self, path: Path, rm: RodMesh) -> None:
        store(path, pickle.dumps(rm, protocol=pickle.HIGHEST_PROTOCOL), "*.pickle", MAX_BYTES, "mesh")
