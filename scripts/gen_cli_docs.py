"""Generate docs/cli.md from the argparse parser, and the tables of docs/formats.md (rig and campaign effects,
tolerance defaults, robot formats) from the registries (``--check`` exits 1 when either is stale; used by the
tests). The rendering is :mod:`rodlab.app.cli.docgen`."""
from __future__ import annotations

import sys
from pathlib import Path

from rodlab.app.cli.docgen import render_cli, render_tables
from rodlab.fileio import write_generated

DOC = Path(__file__).resolve().parents[1] / "docs" / "cli.md"
FORMATS = DOC.with_name("formats.md")


def render_formats() -> str:
    """docs/formats.md with the tables between the markers taken from the registries."""
    return render_tables(FORMATS.read_text(encoding="utf-8"))


if __name__ == "__main__":
    check = "--check" in sys.argv
    status = write_generated(DOC, render_cli(), check) | write_generated(FORMATS, render_formats(), check)
    if not check:
        print(f"wrote {DOC} and the generated tables of {FORMATS}")
    sys.exit(status)
