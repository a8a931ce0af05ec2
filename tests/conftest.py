"""Shared fixtures: the contract examples in ../shared and a design-dict factory."""
from __future__ import annotations

import copy
import sys
from pathlib import Path

import pytest

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared"
EXAMPLES = SHARED / "examples"
ROD1 = ROOT / "rodlab" / "data" / "rods" / "rod1.rod.toml"


@pytest.fixture
def examples() -> Path:
    if not EXAMPLES.is_dir():
        pytest.skip("../shared/examples is not present beside the repository")
    return EXAMPLES


@pytest.fixture
def rod1_dict() -> dict:
    """Parsed rod 1# design, to be modified by a test."""
    return copy.deepcopy(tomllib.loads(ROD1.read_text()))


def write_toml(path: Path, data: dict) -> Path:
    """Minimal TOML writer for test designs (tables of scalars, one level of nesting)."""
    lines = []
    scalars = {k: v for k, v in data.items() if not isinstance(v, dict)}
    tables = {k: v for k, v in data.items() if isinstance(v, dict)}

    def fmt(v):
        if isinstance(v, str):
            return f'"{v}"'
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, float) and v != v:
            return "nan"
        if isinstance(v, float) and v in (float("inf"), float("-inf")):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    for k, v in scalars.items():
        lines.append(f"{k} = {fmt(v)}")
    for name, tbl in tables.items():
        sub = {k: v for k, v in tbl.items() if isinstance(v, dict)}
        flat = {k: v for k, v in tbl.items() if not isinstance(v, dict)}
        if flat or not sub:
            lines.append(f"[{name}]")
            lines.extend(f"{k} = {fmt(v)}" for k, v in flat.items())
        for sname, stbl in sub.items():
            lines.append(f"[{name}.{sname}]")
            lines.extend(f"{k} = {fmt(v)}" for k, v in stbl.items())
    path.write_text("\n".join(lines) + "\n")
    return path
