"""A rig recording's header: its ``# key: value`` lines and its column names (contract ``rodlab.rig/1``)."""
from __future__ import annotations

from pathlib import Path

from rodlab.core.errors import did_you_mean

from .errors import RigError

__all__ = ["FORMAT_RIG", "COLUMNS", "OPTIONAL_COLUMNS", "split_header", "read_header", "check_header",
           "unread_unit_lines", "LOAD_BY_MASS", "LOAD_BY_CELL"]

FORMAT_RIG = "rodlab.rig/1"
COLUMNS = ("time_s", "step", "repeat", "phase", "load_axis", "mass_kg", "disp_x_mm", "disp_y_mm", "disp_z_mm")
OPTIONAL_COLUMNS = ("temp_C", "force_N")


def split_header(lines: list[str]) -> tuple[dict[str, str], int]:
    """The ``# key: value`` lines before the CSV header, and the index of the first other line."""
    meta: dict[str, str] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        body = lines[i].lstrip("#").strip()
        if ":" in body:
            k, v = body.split(":", 1)
            meta[k.strip()] = v.strip()
        i += 1
    return meta, i


def read_header(text: str) -> dict[str, str]:
    """The ``# key: value`` header of a recording's text (``rod``, ``format``, ``plan_hash``, ...)."""
    return split_header(text.splitlines())[0]


def check_header(header: list[str], p: Path, line: int) -> None:
    """Every column known, every required one present, none twice."""
    for col in header:
        if col not in COLUMNS + OPTIONAL_COLUMNS:
            absent = [c for c in COLUMNS + OPTIONAL_COLUMNS if c not in header]     # a column the file has is no fix
            missing = [c for c in COLUMNS if c not in header]
            hint = did_you_mean(col, missing, units=True) or did_you_mean(col, absent, units=True)
            raise RigError(f"unknown column {col!r}; expected {list(COLUMNS + OPTIONAL_COLUMNS)}." + hint,
                           path=p, line=line, key=col)
    for col in COLUMNS:
        if col not in header:
            raise RigError(f"missing column {col!r}", path=p, line=line, key=col)
    if len(set(header)) != len(header):
        dup = [c for c in header if header.count(c) > 1][0]
        raise RigError(f"duplicated column {dup!r}", path=p, line=line, key=dup)


#: the ``# load_N:`` header line rodlab writes to document the load (not read): by mass, or by the load cell
LOAD_BY_MASS = "mass_kg * 9.80665"
LOAD_BY_CELL = "force_N (load cell"
_LOAD_SOURCES = (LOAD_BY_MASS, "force_N")     # what the line may say and pass unwarned


def unread_unit_lines(meta: dict[str, str]) -> list[str]:
    """Header lines that try to redefine a column or the load (``# load_N: mass_lb * 4.448``, ``# mass_kg: lb``):
    rodlab reads no units or formulas from a recording's header (its columns' names fix their units), so such a
    line changes nothing; said, not silent. rodlab's own documenting ``load_N`` lines pass."""
    edited = [k for k, v in meta.items() if k in COLUMNS + OPTIONAL_COLUMNS
              or (k == "load_N" and not v.startswith(_LOAD_SOURCES))]
    return [f"the header line '# {k}: {meta[k]}' is not read: a recording takes no units or formulas from its header, "
            f"the columns' names fix their units and the load is mass_kg x 9.80665 N/kg, or the force_N column "
            f"(docs/formats.md): convert the values in the columns instead" for k in edited]
