"""A simulated device's end of a real pseudo-terminal, published under a stable symlink (the profile's port), and
its serving thread's life (start, stop, context manager).

Shared by the one-port simulator (:mod:`.simdevice`) and the instrument simulators (:mod:`.siminstruments`): the
pty is opened raw on both ends and the link is swapped atomically, so a replug (close, reopen) gives the reader a
new device behind the same path.
"""
from __future__ import annotations

import os
import threading
import tty

__all__ = ["PtyLink"]


class PtyLink:
    """Mixin for a simulator with ``link`` (a :class:`~pathlib.Path`), ``_master`` / ``_slave`` file descriptors, a
    ``_stop`` event, a ``_thread`` (None until started) and ``_run`` (the device's loop on the master end)."""

    #: the serving thread's name (None: ``sim-`` and the class name)
    thread_name: str | None = None

    def start(self):
        self._open_pty()
        self._thread = threading.Thread(target=self._run, name=self.thread_name or f"sim-{type(self).__name__}",
                                        daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()
        if self._thread:
            self._thread.join(timeout=5)
        self._close_pty()
        if self.link.is_symlink():
            self.link.unlink()

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()

    def _open_pty(self) -> None:
        master, slave = os.openpty()
        tty.setraw(master)
        tty.setraw(slave)
        self._master, self._slave = master, slave
        tmp = self.link.with_name(self.link.name + ".new")
        if tmp.is_symlink() or tmp.exists():
            tmp.unlink()
        tmp.symlink_to(os.ttyname(slave))
        os.replace(tmp, self.link)

    def _close_pty(self) -> None:
        for fd in (self._master, self._slave):
            if fd is not None:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._master = self._slave = None

    @property
    def port(self) -> str:
        return str(self.link)
