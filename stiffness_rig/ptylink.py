"""A simulated device's end of a real pseudo-terminal, published under a stable symlink (the profile's port).

Shared by the one-port simulator (:mod:`.simdevice`) and the instrument simulators (:mod:`.siminstruments`): the
pty is opened raw on both ends and the link is swapped atomically, so a replug (close, reopen) gives the reader a
new device behind the same path.
"""
from __future__ import annotations

import os
import tty

__all__ = ["PtyLink"]


class PtyLink:
    """Mixin for a simulator with ``link`` (a :class:`~pathlib.Path`) and ``_master`` / ``_slave`` file descriptors."""

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
