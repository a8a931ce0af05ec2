"""gmsh started without taking the process's signal handlers.

``gmsh.initialize`` installs its own C handlers for SIGTERM, SIGHUP and SIGPIPE (and leaves them after
``gmsh.finalize``), in whichever thread it runs: a command that had meshed could no longer be stopped cleanly.
``kill`` then ended ``rodlab demo`` at once (exit 143) with its CAD child left running, and a closed pipe (``rodlab
... | head``) ended a command silently instead of raising Python's ``BrokenPipeError``. :func:`initialize_gmsh`
keeps each signal's disposition as it was: every catchable signal's ``sigaction`` is read before gmsh starts and
written back where gmsh changed it (libc's ``sigaction`` through ctypes, opaque buffers: process-wide, safe from the
mesher's background thread). Where libc cannot be loaded (Windows) gmsh is started as it is.
"""
from __future__ import annotations

import ctypes
import logging
import signal

__all__ = ["initialize_gmsh"]

log = logging.getLogger(__name__)

#: bytes kept of one ``struct sigaction`` (glibc's is 152 on x86-64, musl's and macOS's smaller)
_SIGACTION_BYTES = 512


def _libc():
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc if hasattr(libc, "sigaction") else None
    except (OSError, TypeError):
        return None


def _catchable() -> list[int]:
    skip = {getattr(signal, n) for n in ("SIGKILL", "SIGSTOP") if hasattr(signal, n)}
    return [int(s) for s in signal.Signals if s not in skip]


def _read(libc, signals: list[int]) -> dict[int, bytes]:
    out = {}
    for sig in signals:
        buf = ctypes.create_string_buffer(_SIGACTION_BYTES)
        if libc.sigaction(sig, None, buf) == 0:
            out[sig] = buf.raw
    return out


def initialize_gmsh() -> None:
    """``gmsh.initialize`` (no configuration files, not interruptible) with the signal handlers kept."""
    import gmsh

    libc = _libc()
    before = _read(libc, _catchable()) if libc is not None else {}
    gmsh.initialize(readConfigFiles=False, interruptible=False)
    if not before:
        return
    after = _read(libc, list(before))
    for sig, raw in before.items():
        if after.get(sig) != raw:
            buf = ctypes.create_string_buffer(raw, _SIGACTION_BYTES)
            if libc.sigaction(sig, buf, None) != 0:
                log.debug("signal %d's handler could not be restored after gmsh started (errno %d)", sig,
                          ctypes.get_errno())
