"""Write a design with some dotted keys changed, keeping the user's file as it is (comments, order, layout).

Used by ``rodlab update`` to write the rod as built: each changed key's line is rewritten in place (with the
design value kept in a comment), a missing key is added to its table, a missing table (a built-in material's
numbers, a part that took its defaults) is appended; the result is read back as a design before it is written.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

from .design import RodDesign
from .design_io import FORMAT_ROD_V2, design_from_dict, design_to_dict
from .errors import DesignError, FormatError
from .fileio import atomic_write_text
from .tolerances import design_value

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["edited_design_text", "write_edited_design"]


def _table_spans(lines: list[str]) -> dict:
    """{table name: (header line index, end index)}; the top level is ``""``."""
    spans, current, start = {}, "", 0
    for i, raw in enumerate(lines):
        m = re.match(r"^\s*\[\s*([^\]]+?)\s*\]\s*(#.*)?$", raw)
        if m:
            spans[current] = (start, i)
            current, start = m.group(1).strip(), i
    spans[current] = (start, len(lines))
    return spans


def _set_key(lines: list[str], table: str, name: str, value: float, was: float | None) -> list[str]:
    spans = _table_spans(lines)
    note = f"   # design: {was:g}" if was is not None else "   # added by rodlab update"
    if table in spans:
        a, b = spans[table]
        for i in range(a + (1 if table else 0), b):
            if re.match(rf"^\s*{re.escape(name)}\s*=", lines[i]):
                lines[i] = f"{name} = {value:.6g}{note}"
                return lines
        insert = b
        while insert > a + 1 and not lines[insert - 1].strip():
            insert -= 1
        return lines[:insert] + [f"{name} = {value:.6g}{note}"] + lines[insert:]
    return lines + ["", f"[{table}]", f"{name} = {value:.6g}{note}"]


def _material_table(design: RodDesign, name: str) -> dict:
    """A material's numbers as a ``[materials.NAME]`` table (for a built-in material the file does not define)."""
    return design_to_dict(design)["materials"][name]


def _value_of(design: RodDesign, key: str) -> float:
    """The design's value of ``key``; a material's number also for the parts whose keys the tolerances do not list
    (the rings' and holders' materials, whose moduli ``rodlab update --free moduli`` scales)."""
    table, _, name = key.rpartition(".")
    if table.startswith("materials."):
        numbers = design_to_dict(design)["materials"].get(table.split(".", 1)[1], {})
        if numbers.get(name) is not None:
            return float(numbers[name])
    return design_value(design, key)


def edited_design_text(text: str, design: RodDesign, values: dict, header: str = "") -> str:
    """``text`` (the design's file) with the dotted keys of ``values`` set; ``tube.*`` keys are written to
    ``[tube]``, ``materials.NAME.*`` to ``[materials.NAME]`` (created with the material's numbers if absent)."""
    lines = text.splitlines()
    for key, value in values.items():
        was = _value_of(design, key)
        table, _, name = key.rpartition(".")
        if table.startswith("materials.") and table not in _table_spans(lines):
            for k, v in _material_table(design, table.split(".", 1)[1]).items():
                lines = _set_key(lines, table, k, float(v), None) if k != name else lines
        lines = _set_key(lines, table, name, float(value), was)
    if any(k.startswith("joints.") for k in values):       # a declared joint needs the v2 format
        lines = [re.sub(r'^(\s*format\s*=\s*)"rodlab\.rod/1"', rf'\1"{FORMAT_ROD_V2}"', ln) for ln in lines]
    body = "\n".join(lines) + "\n"
    return (header + body) if header else body


def write_edited_design(source_text: str, design: RodDesign, values: dict, out: str | Path, header: str = "") -> Path:
    """Write the edited design to ``out`` atomically, after reading it back as a valid design."""
    text = edited_design_text(source_text, design, values, header)
    try:
        design_from_dict(tomllib.loads(text), out, text)
    except (FormatError, tomllib.TOMLDecodeError) as e:
        raise DesignError(f"the edited design would not be valid ({e}); nothing was written", path=out) from e
    return atomic_write_text(out, text)
