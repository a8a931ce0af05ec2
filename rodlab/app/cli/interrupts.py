"""``kill`` and a closed terminal stop a long command as Ctrl-C does (``rodlab demo``, ``rodlab rig simulator``):
each cleans up on KeyboardInterrupt (the demo stops its CAD child, the simulator removes its link)."""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["kill_as_interrupt"]


def _interrupt(signum, frame):
    raise KeyboardInterrupt


@contextmanager
def kill_as_interrupt():
    """In the block SIGTERM and SIGHUP raise KeyboardInterrupt; the handlers before are restored after it. Only the
    signals that exist (no SIGHUP on Windows), and only from the main thread (elsewhere: nothing changes)."""
    sigs = [getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n)]
    on_main = threading.current_thread() is threading.main_thread()
    before = {sig: signal.signal(sig, _interrupt) for sig in sigs} if on_main else {}
    try:
        yield
    finally:
        for sig, handler in before.items():
            signal.signal(sig, handler)
