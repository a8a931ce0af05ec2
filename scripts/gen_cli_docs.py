"""Generate docs/cli.md from the argparse parser, and the tables of docs/formats.md (rig and campaign effects,
tolerance defaults, robot formats) and docs/rig.md (instrument protocols) from the registries (``--check``
exits 1 when any is stale; used by the tests). The rendering is :mod:`rodlab.app.cli.docgen`."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from rodlab.app.cli.docgen import DOC_TABLES, render_cli, render_tables
from rodlab.core.fileio import write_generated

DOC = Path(__file__).resolve().parents[1] / "docs" / "cli.md"


if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="write nothing; exit 1 when a generated page is stale")
    check = ap.parse_args().check
    status = write_generated(DOC, render_cli(), check)
    for page, tables in DOC_TABLES.items():
        path = DOC.with_name(page)
        status |= write_generated(path, render_tables(path.read_text(encoding="utf-8"), tables), check)
    if not check:
        print(f"wrote {DOC} and the generated tables of {', '.join(DOC_TABLES)}")
    sys.exit(status)
