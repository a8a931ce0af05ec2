"""What the source-tree tests (test_import_policy, test_private_imports) share: the package folders pyproject
installs and the dotted package of a source file."""
from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
#: installed package name -> its folder in the repository (pyproject's package-dir)
PACKAGE_DIRS = PYPROJECT["tool"]["setuptools"]["package-dir"]


def package_of(path: Path) -> str | None:
    """The dotted package a source file sits in (for relative imports), or None outside the packages."""
    for name, folder in sorted(PACKAGE_DIRS.items(), key=lambda kv: -len(kv[1])):
        try:
            rel = path.parent.relative_to(ROOT / folder)
        except ValueError:
            continue
        return ".".join([name, *rel.parts]) if rel.parts else name
    return None
