"""Files are written atomically (a crash leaves the old file or the new one) without destroying what the path
is: a device such as /dev/null is written into, not renamed over (a new-user trial's `-o /dev/null` had replaced
the machine's /dev/null by a regular file), a symbolic link keeps pointing at its file."""
from __future__ import annotations

import os
import stat

from rodlab.app.cli import main
from rodlab.core.fileio import atomic_write_text


def test_a_device_is_written_into_not_replaced(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)          # a reader, so the writer does not block
    try:
        atomic_write_text(fifo, "hello\n")
        assert os.read(fd, 100) == b"hello\n"
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    fd = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
    try:                                                        # as a command's -o (a pipe, like /dev/null)
        assert main(["fea", "rod1", "--model", "calc", "-o", str(fifo)]) == 0
        assert b'"C_F_mm_per_N"' in os.read(fd, 1 << 16)
    finally:
        os.close(fd)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)


def test_a_symbolic_link_keeps_pointing_at_its_file(tmp_path):
    target = tmp_path / "real.json"
    target.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(target)
    atomic_write_text(link, "new")
    assert link.is_symlink() and target.read_text() == "new"
