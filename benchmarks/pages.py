"""Writing a benchmark's page: its table, then the hand-written notes kept beside the script."""
from __future__ import annotations

from pathlib import Path

from rodlab.core.fileio import atomic_write_text

__all__ = ["write_page"]


def write_page(out: Path, lines: list[str], notes_file: Path) -> None:
    """``lines`` plus the notes in ``notes_file`` (if it exists) into ``out``, atomically."""
    if notes_file.exists():
        lines = [*lines, "", notes_file.read_text().strip()]
    atomic_write_text(out, "\n".join(lines) + "\n")
    print(f"wrote {out}")
