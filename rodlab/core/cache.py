"""rodlab's per-user cache folder, shared by the caches of the domain packages (meshes, assembly plans).

Folder: ``$RODLAB_CACHE_DIR``, else ``$XDG_CACHE_HOME/rodlab``, else ``~/.cache/rodlab``; ``RODLAB_CACHE_DIR=off``
(or ``rodlab fea --no-cache``) turns every cache off. Each cache keeps its files in a sub-folder of its own and
prunes it to a size limit, least recently used first (:func:`prune`).
"""
from __future__ import annotations

import hashlib
import logging
import os
import sys
from importlib import metadata
from pathlib import Path

from .fileio import atomic_write_bytes

__all__ = ["CACHE_ENV", "cache_root", "cache_subfolder", "prune", "sources_digest", "code_digest", "load", "store"]

log = logging.getLogger(__name__)

#: the environment variable naming the cache folder (``off`` turns caching off)
CACHE_ENV = "RODLAB_CACHE_DIR"


def cache_root() -> Path | None:
    """The cache folder, or None when ``RODLAB_CACHE_DIR`` is ``off`` (or there is no home folder)."""
    root = os.environ.get(CACHE_ENV, "").strip()
    if root.lower() in ("off", "0", "none", "false"):
        return None
    if root:
        return Path(root).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME", "").strip()
    try:
        return (Path(xdg) if xdg else Path.home() / ".cache") / "rodlab"
    except RuntimeError:                                  # no home folder: no cache
        return None


def cache_subfolder(name: str) -> Path | None:
    """The sub-folder ``name`` of :func:`cache_root`, or None when caching is off."""
    root = cache_root()
    return None if root is None else root / name


def prune(folder: Path, pattern: str, max_bytes: int) -> None:
    """Delete the files ``pattern`` of ``folder`` beyond ``max_bytes`` in total, newest (most recently used)
    kept first. Another process may prune the same folder at the same time: a file gone already is skipped."""
    sized = []
    for p in folder.glob(pattern):
        try:
            st = p.stat()
        except FileNotFoundError:
            continue
        sized.append((st.st_mtime, st.st_size, p))
    total = 0
    for _, size, p in sorted(sized, key=lambda t: t[0], reverse=True):
        total += size
        if total > max_bytes:
            p.unlink(missing_ok=True)


def sources_digest(module_name: str, extra: tuple[Path, ...] = ()) -> str:
    """SHA-256 of the sources of the package ``module_name`` belongs to (every ``*.py`` of its folder) and of the
    files ``extra``: a cache keyed on it is never served a result an older version of that code made."""
    here = Path(sys.modules[module_name].__file__).resolve().parent
    h = hashlib.sha256()
    for f in sorted(here.glob("*.py")) + list(extra):
        h.update(f.name.encode() + f.read_bytes())
    return h.hexdigest()


def code_digest(module_name: str, extra: tuple[Path, ...] = (), dists: tuple[str, ...] = ()) -> str:
    """:func:`sources_digest` and the installed versions of the distributions ``dists`` (``?`` for one not
    installed): what a cache entry made by that code with those packages depends on."""
    h = hashlib.sha256(sources_digest(module_name, extra).encode())
    for dist in dists:
        try:
            h.update(f"{dist} {metadata.version(dist)}".encode())
        except metadata.PackageNotFoundError:
            h.update(f"{dist} ?".encode())
    return h.hexdigest()


def store(path: Path, data: bytes, pattern: str, max_bytes: int, what: str) -> None:
    """Write the cache entry ``path`` atomically, then prune its folder's ``pattern`` files to ``max_bytes``; a
    folder that cannot be written (a read-only home) leaves the run uncached, with a warning naming ``what``."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(path, data)
        prune(path.parent, pattern, max_bytes)
    except OSError as e:
        log.warning("%s cache %s not written (%s)", what, path, e)


def load(path: Path, read, fits, what: str):
    """The cache entry ``path`` as ``read(path)`` gives it, if ``fits(entry)``; else None: missing, another user's
    (not read: a shared folder), unreadable, or not fitting (each but the first with a warning naming ``what``).
    An entry kept is marked recently used (pruned last; a read-only cache still serves)."""
    try:
        if path.stat().st_uid != os.getuid():
            log.warning("%s cache %s belongs to another user: not read, made again", what, path)
            return None
        entry = read(path)
    except FileNotFoundError:
        return None
    except Exception as e:                            # a truncated or foreign file: made again and replaced
        log.warning("%s cache %s unreadable (%s): made again", what, path, e)
        return None
    if not fits(entry):
        log.warning("%s cache %s does not fit: made again", what, path)
        return None
    try:
        os.utime(path)
    except OSError:
        pass
    return entry
