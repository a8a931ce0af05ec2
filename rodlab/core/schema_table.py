"""The table schema of rodlab's CSV formats, and every problem a CSV text has against one.

A table schema (``rodlab/schemas/*.table.json``) states the ``# key: value`` comment lines before the header
(``comments``: type ``string`` or ``vector`` of ``size`` numbers, ``required``, ``const``) and the columns
(``columns``: ``name``, ``type`` number / integer / string, ``required``, ``nullable`` for empty cells,
``enum``, ``minimum`` / ``exclusiveMinimum``, ``unit``; a column with ``"joints": true`` and a name such as
``q{i}`` stands for q1..qn, n being however many the header has). ``unique`` lists column groups whose values
may not repeat; ``together`` groups of columns that are all present or all absent; ``one_of`` alternative groups
of which exactly one is present (a campaign's x, y, z or its raw sensor readings).
"""
from __future__ import annotations

import csv
import math
import re

from .errors import did_you_mean, joint_alias_number
from .fileio import separator_problem
from .schema import Problem

__all__ = ["table_problems", "MAX_PROBLEMS"]

#: problems listed per file before the rest are counted
MAX_PROBLEMS = 50
#: a number written with a decimal comma (quoted in a comma-separated file)
DECIMAL_COMMA = re.compile(r"[+-]?[0-9]*,[0-9]+")


def _comments(lines: list[str]) -> tuple[dict, int]:
    """``{key: (line, value)}`` of the leading comment lines and the index of the header line."""
    meta, i = {}, 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        body = lines[i].strip().lstrip("#").strip()
        if ":" in body:
            k, v = body.split(":", 1)
            meta.setdefault(k.strip(), (i + 1, v.strip()))
        i += 1
    return meta, i


def _comment_problems(meta: dict, spec: dict, path: str) -> list[Problem]:
    out = []
    for key, c in spec.items():
        if key not in meta:
            if c.get("required"):
                out.append(Problem(path, f"missing comment line '# {key}: ...' before the header", 1, key,
                                   f"add '# {key}: {c.get('const', '...')}'"))
            continue
        line, value = meta[key]
        if "const" in c and value != c["const"]:
            out.append(Problem(path, f"expected {c['const']!r}, got {value!r}", line, key, f"write {c['const']}"))
        if c.get("type") == "vector":
            try:
                nums = [float(v) for v in value.split(",")]
            except ValueError:
                nums = None
            if nums is None or len(nums) != c["size"] or not all(math.isfinite(v) for v in nums):
                out.append(Problem(path, f"expected {c['size']} comma-separated finite numbers [{c.get('unit', '-')}], "
                                   f"got {value!r}", line, key, f"write e.g. '# {key}: " +
                                   ", ".join(["0"] * c["size"]) + "'"))
    return out


def _columns(header: list[str], schema: dict) -> dict:
    """Column name -> its spec, the joint pattern expanded to the q-columns the header has (at least q1)."""
    cols = {}
    for c in schema["columns"]:
        if c.get("joints"):
            pat = re.compile("^" + re.escape(c["name"]).replace(r"\{i\}", r"([1-9][0-9]*)") + "$")
            n = max([int(m.group(1)) for h in header if (m := pat.match(h))] or [1])
            for i in range(1, n + 1):
                cols[c["name"].replace("{i}", str(i))] = c
        else:
            cols[c["name"]] = c
    return cols


def _header_problems(header: list[str], cols: dict, schema: dict, path: str, line: int) -> list[Problem]:
    renames = _renames(header, cols, schema)
    if len(renames) >= 3:                      # a header in another convention: one problem, every rename
        out = [Problem(path, f"the header names {len(renames)} columns otherwise than the format", line,
                       next(iter(renames)), "rename " + ", ".join(f"{h!r} to {n}" for h, n in renames.items()))]
    else:
        out = []
    expected = _expected(cols)
    for h in header:
        if h not in cols and not (len(renames) >= 3 and h in renames):
            out.append(Problem(path, f"unknown column {h!r}; expected {expected}", line, h,
                               did_you_mean(h, cols, units=True).strip() or "remove it or rename it"))
    for name, c in cols.items():
        if c.get("required") and name not in header and not (len(renames) >= 3 and name in renames.values()):
            out.append(Problem(path, f"missing column {name!r}", line, name, f"add the column {name}"))
    for h in sorted({h for h in header if header.count(h) > 1}):
        out.append(Problem(path, f"duplicated column {h!r}", line, h, "keep one"))
    for group in schema.get("together", []):
        have = [g for g in group if g in header]
        if have and len(have) != len(group):
            missing = [g for g in group if g not in header]
            out.append(Problem(path, f"columns {group} go together; missing {missing}", line, missing[0],
                               f"add {missing} or remove {have}"))
    out += _one_of_problems(header, schema, path, line)
    return out


def _renames(header: list[str], cols: dict, schema: dict) -> dict:
    """{the user's column: the format's} for each unknown column whose name says which column it is (``Achse1`` ->
    q1, ``X [mm]`` -> x_mm): the joints' columns of every number the header has, not only those it expands."""
    names = list(cols) + [c["name"].replace("{i}", str(i)) for c in schema["columns"] if c.get("joints")
                          for i in range(1, len(header) + 1)]
    out = {}
    numbers = [n for h in header if h not in cols and (n := joint_alias_number(h)) is not None]
    shift = 1 if 0 in numbers else 0              # J0, J1, ...: counted from 0 (a review: J1 had become q1)
    for h in header:
        if h in cols:
            continue
        n = joint_alias_number(h)
        if shift and n is not None and f"q{n + 1}" in names and f"q{n + 1}" not in header:
            out[h] = f"q{n + 1}"
            continue
        hint = re.search(r"`([^`]+)`", did_you_mean(h, names, units=True))
        if hint and hint.group(1) in names and hint.group(1) not in header:
            out[h] = hint.group(1)
    return out


def _expected(cols: dict) -> str:
    """The expected columns, the joints' as ``q1, q2, ...`` (a trial: the list had shown only q1)."""
    shown = [c for c in cols if not re.fullmatch(r"q[0-9]+", c)]
    joints = "q1, q2, ... (one per joint, degrees), " if len(shown) < len(cols) else ""
    return "[" + joints + ", ".join(shown) + "]"


def _one_of_problems(header: list[str], schema: dict, path: str, line: int) -> list[Problem]:
    out = []
    for alternatives in schema.get("one_of", []):
        present = [g for g in alternatives if any(c in header for c in g)]
        if len(present) == 1:
            continue
        names = " or ".join(",".join(g) for g in alternatives)
        msg = "has columns of " + " and ".join(",".join(g) for g in present) if present else "has none of them"
        out.append(Problem(path, f"expected the columns {names}, exactly one set; the header {msg}", line,
                           alternatives[0][0], "keep one set of columns"))
    return out


#: what an empty reading of a point needs (a device trial: "write a value" had been the advice for a sensor that
#: lost the ball); the schema check and the campaign reader say it alike
#: the columns that are a measured point's readings (a campaign's x/y/z or raw s1-s3, a probe file's x/y/z): an
#: empty one of these gets :data:`EMPTY_READING_FIX`; any other empty mm cell (a length, a sigma) the plain fix
READING_COLUMNS = frozenset({"x_mm", "y_mm", "z_mm", "s1_mm", "s2_mm", "s3_mm"})
EMPTY_READING_FIX = ("a point without this reading (the sensor lost the ball, the instrument missed the target) cannot "
                     "be used: measure the point again, or delete its row")


def _cell_problem(cell: str, c: dict, name: str, path: str, line: int) -> Problem | None:
    s = cell.strip()
    if not s:
        if c.get("nullable"):
            return None
        return Problem(path, "empty cell", line, name, EMPTY_READING_FIX if name in READING_COLUMNS else "write a value")
    if c["type"] == "string":
        if "enum" in c and s not in c["enum"]:
            return Problem(path, f"expected one of {c['enum']}, got {s!r}", line, name,
                           did_you_mean(s, c["enum"]).strip() or f"use one of {c['enum']}")
        return None
    try:
        v = float(s)
    except ValueError:
        if (fix := decimal_comma_fix(s)) is not None:
            return Problem(path, f"expected a number, got {s!r}: a decimal comma (a locale's export)", line, name, fix)
        return Problem(path, f"expected a number, got {s!r}", line, name, "write a number with a decimal point")
    if not math.isfinite(v):
        return Problem(path, f"expected a finite number, got {s!r}", line, name, "write a finite number")
    if c["type"] == "integer" and v != int(v):
        return Problem(path, f"expected an integer, got {s!r}", line, name, "write a whole number")
    for k, op, bad in (("minimum", ">=", lambda a, b: a < b), ("exclusiveMinimum", ">", lambda a, b: a <= b)):
        if k in c and bad(v, c[k]):
            return Problem(path, f"expected a number {op} {c[k]} [{c.get('unit', '-')}], got {s!r}", line, name,
                           "correct the value")
    return None


#: columns a copied row may differ in and still be a copy (when, at what temperature: not what was measured)
NOT_MEASURED = ("time_s", "temp_C")


def decimal_comma_fix(cell: str) -> str | None:
    """How to mend a number written with a decimal comma (``"40,7296"``), or None for any other text."""
    s = cell.strip()
    return f"write {s.replace(',', '.')}: export the file with a decimal point" if DECIMAL_COMMA.fullmatch(s) else None


def sub_micrometre(values_mm) -> bool:
    """Some reading [mm] carries digits below a micrometre: rows equal in every reading and joint angle are then a
    copy, not a repeat of a pose (an export rounded to um could make a repeat equal)."""
    return any(abs(v * 1e3 - round(v * 1e3)) > 1e-6 for v in values_mm)


def _readings_mm(header, row) -> list[float]:
    """The row's numeric cells of ``*_mm`` columns (its readings), those that parse."""
    out = []
    for name, cell in zip(header, row):
        if name.endswith("_mm"):
            try:
                out.append(float(cell))
            except ValueError:
                pass
    return out


def _row_problems(lines, start: int, header, cols, schema, path) -> list[Problem]:
    out, seen, rows = [], {}, 0
    groups = [tuple(g) for g in schema.get("unique", []) if all(k in header for k in g)]
    numbered = [(k, row) for k, row in enumerate(csv.reader(lines[start:]), start=start + 1)
                if row and "".join(row).strip() and not row[0].lstrip().startswith("#")]
    if numbered and schema.get("cut_last_row") and len(numbered[-1][1]) < len(header):
        numbered = numbered[:-1]                  # a sample cut off: the readers leave it out, with a warning
    for k, row in numbered:
        rows += 1
        if len(row) != len(header):
            out.append(Problem(path, f"expected {len(header)} cells, got {len(row)}", k, None,
                               "one cell per header column (empty cells keep their commas)"))
            continue
        for name, cell in zip(header, row):
            if name in cols and (p := _cell_problem(cell, cols[name], name, path, k)):
                out.append(p)
        for g in groups:
            key = tuple(row[header.index(c)].strip() for c in g)
            content = tuple(c.strip() for name, c in zip(header, row) if name not in g and name not in NOT_MEASURED)
            if (g, key) in seen:
                first, same = seen[(g, key)]
                out.append(Problem(path, f"{dict(zip(g, key))} appears twice (also on line {first})", k, g[-1],
                                   "delete the repeated row" if same == content else "number every row uniquely"))
            elif (g, content) in seen and sub_micrometre(_readings_mm(header, row)):
                out.append(Problem(path, f"repeats line {seen[(g, content)]} in every cell but {', '.join(g)} (a copy: "
                                   "a measurement repeated at the same pose reads differently by the instrument's "
                                   "noise)", k, g[-1], "delete the copied rows"))
            seen.setdefault((g, key), (k, content))
            seen.setdefault((g, content), k)
    if rows == 0:
        out.append(Problem(path, "no data rows after the header", start, None, "add the measurements"))
    return _one_decimal_comma(out, path)


def _one_decimal_comma(problems: list[Problem], path: str) -> list[Problem]:
    """A file written with decimal commas: its first such cell named, the others counted, not each listed."""
    commas = [p for p in problems if "a decimal comma" in p.message]
    if len(commas) <= 1:
        return problems
    rest = [p for p in problems if p not in commas]
    return [commas[0], *rest, Problem(path, f"... and {len(commas) - 1} more cells with a decimal comma", None, None,
                                      "export the file with a decimal point (a locale's setting)")]


def table_problems(text: str, schema: dict, path: str = "") -> list[Problem]:
    """Every problem of the CSV ``text`` against the table ``schema`` (the first :data:`MAX_PROBLEMS`, then a
    count of the rest)."""
    lines = text.splitlines()
    meta, i = _comments(lines)
    out = _comment_problems(meta, schema.get("comments", {}), path)
    if i >= len(lines):
        return out + [Problem(path, "no header line", i or None, None, "add the column header line")]
    if (problem := separator_problem(lines[i])) is not None:
        return out + [Problem(path, problem.split(": ", 1)[0], i + 1, None, problem.split(": ", 1)[1])]
    header = [h.strip() for h in next(csv.reader([lines[i]]))]
    cols = _columns(header, schema)
    out += _header_problems(header, cols, schema, path, i + 1)
    out += _row_problems(lines, i + 1, header, cols, schema, path)
    if len(out) > MAX_PROBLEMS:
        out = out[:MAX_PROBLEMS] + [Problem(path, f"... and {len(out) - MAX_PROBLEMS} more problems")]
    return out
