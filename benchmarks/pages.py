"""Writing a benchmark's page: its table, then the hand-written notes kept beside the script; and the
environment the benchmarks run a user's commands in."""
from __future__ import annotations

import os
from pathlib import Path

from rodlab.core.fileio import atomic_write_text

__all__ = ["write_page", "user_env"]


def write_page(out: Path, lines: list[str], notes_file: Path) -> None:
    """``lines`` plus the notes in ``notes_file`` (if it exists) into ``out``, atomically."""
    if notes_file.exists():
        lines = [*lines, "", notes_file.read_text().strip()]
    atomic_write_text(out, "\n".join(lines) + "\n")
    print(f"wrote {out}")


def user_env(**extra: str) -> dict:
    """This environment as a user's shell has it, plus ``extra``: Python writes its bytecode cache (this
    workplace sets PYTHONDONTWRITEBYTECODE, which would compile rodlab's modules anew at every command)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env.update(extra)
    return env
