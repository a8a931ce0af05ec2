"""A per-user cache of rod meshes: a designer who reruns ``rodlab fea`` on the same design and size skips gmsh.

The key is the SHA-256 of everything the mesh depends on: the design as a ``rodlab.rod`` table (every dimension,
part and material), the size, grading and half / whole, the mesh order, gmsh's version and
:data:`MESH_REVISION` (raised whenever :func:`geometry.mesh_rod` changes what it makes). A hit is the pickled
:class:`~rodlab.core.fem_mesh.RodMesh` (~2 MB for rod 1#'s default half mesh); a file that cannot be read is
meshed again and replaced. Files are written atomically; the folder is pruned to :data:`MAX_BYTES`, oldest first.

Folder: ``$RODLAB_CACHE_DIR/meshes``, else ``$XDG_CACHE_HOME/rodlab/meshes``, else ``~/.cache/rodlab/meshes``;
``RODLAB_CACHE_DIR=off`` (or ``rodlab fea --no-cache``) turns it off. Only rodlab writes there: the files are
pickles, read back by the user who wrote them.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import pickle
from pathlib import Path

from rodlab.core.design import RodDesign
from rodlab.core.design_io import design_to_dict
from rodlab.core.fem_mesh import RodMesh
from rodlab.core.fileio import atomic_write_bytes

__all__ = ["MeshCache", "MESH_REVISION", "MAX_BYTES", "cache_folder"]

log = logging.getLogger(__name__)

#: raise when mesh_rod makes a different mesh from the same inputs (old entries are then never hit)
MESH_REVISION = 1
#: the folder's size limit [bytes]
MAX_BYTES = 500_000_000


def cache_folder() -> Path | None:
    """Where meshes are cached, or None when ``RODLAB_CACHE_DIR`` is ``off``."""
    root = os.environ.get("RODLAB_CACHE_DIR", "").strip()
    if root.lower() in ("off", "0", "none", "false"):
        return None
    if root:
        return Path(root).expanduser() / "meshes"
    xdg = os.environ.get("XDG_CACHE_HOME", "").strip()
    return (Path(xdg) if xdg else Path.home() / ".cache") / "rodlab" / "meshes"


class MeshCache:
    """A :class:`~fea.compute.Mesher` that remembers: ``MeshCache(mesh_rod)(design, size_mm=..., grading=...,
    half=...)`` returns the cached mesh or meshes, stores and returns it. ``hits`` / ``misses`` count calls."""

    def __init__(self, mesher, folder: Path | None | str = "default") -> None:
        self.mesher = mesher
        self.folder = cache_folder() if folder == "default" else (Path(folder) if folder else None)
        self.hits = self.misses = 0

    def key(self, design: RodDesign, **kw) -> str:
        """The SHA-256 naming the mesh of ``design`` with the mesher's keywords ``kw``."""
        import gmsh
        text = json.dumps({"design": design_to_dict(design), "mesher": {k: kw[k] for k in sorted(kw)},
                           "gmsh": gmsh.__version__, "revision": MESH_REVISION}, sort_keys=True, default=str)
        return hashlib.sha256(text.encode()).hexdigest()

    def __call__(self, design: RodDesign, **kw) -> RodMesh:
        if self.folder is None:
            return self.mesher(design, **kw)
        path = self.folder / f"{self.key(design, **kw)}.pickle"
        found = self._read(path)
        if found is not None:
            self.hits += 1
            log.info("mesh of %s from the cache (%s)", design.name, path)
            return found
        self.misses += 1
        rm = self.mesher(design, **kw)
        self._write(path, rm)
        return rm

    def _read(self, path: Path) -> RodMesh | None:
        try:
            with open(path, "rb") as f:
                rm = pickle.load(f)
        except FileNotFoundError:
            return None
        except Exception as e:                            # a truncated or foreign file: mesh again, replace it
            log.warning("mesh cache %s unreadable (%s): meshing again", path, e)
            return None
        if not isinstance(rm, RodMesh):
            log.warning("mesh cache %s holds no rod mesh: meshing again", path)
            return None
        os.utime(path)                                     # recently used: pruned last
        return rm

    def _write(self, path: Path, rm: RodMesh) -> None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            atomic_write_bytes(path, pickle.dumps(rm, protocol=pickle.HIGHEST_PROTOCOL))
            self._prune()
        except OSError as e:                              # a read-only home: the run goes on uncached
            log.warning("mesh cache %s not written (%s)", path, e)

    def _prune(self) -> None:
        files = sorted(self.folder.glob("*.pickle"), key=lambda p: p.stat().st_mtime, reverse=True)
        total = 0
        for p in files:
            total += p.stat().st_size
            if total > MAX_BYTES:
                p.unlink(missing_ok=True)
