"""Machine-readable schemas of rodlab's file formats, and every problem a file has against its schema.

The schemas ship in ``rodlab/schemas``: JSON Schema (draft 2020-12) for the JSON and TOML formats (a TOML
file is checked as the table it parses to), and a small table schema for the CSV formats
(:mod:`rodlab.core.schema_table`). :func:`check_file` names a file's format (from its ``format`` key, its
``# format:`` comment or its suffix) and returns every schema problem at once, each with the line and key
where it can be located, what was expected and a fix. The readers' own rules beyond the schema (a symmetric
C_F, a fixture's world position among its positions, holds that keep their load) are run after the schema
by ``rodlab validate``.
"""
from __future__ import annotations

import json
import re
import sys
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from pathlib import Path

from .errors import did_you_mean
from .fileio import read_toml, toml_problem

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["FormatSpec", "FORMATS", "Problem", "FileCheck", "load_schema", "sniff_format", "check_file",
           "data_problems", "require_schema", "read_toml_checked"]


@dataclass(frozen=True)
class FormatSpec:
    """One file format: its id, how it is stored (json, toml, csv), its schema file and usual suffixes."""

    id: str
    kind: str
    schema_file: str
    suffixes: tuple
    title: str


FORMATS: dict[str, FormatSpec] = {s.id: s for s in (
    FormatSpec("rodlab.rod/1", "toml", "rod.schema.json", (".rod.toml",), "rod design"),
    FormatSpec("rodlab.rod/2", "toml", "rod2.schema.json", (".rod.toml",), "rod design with declared compliant joints"),
    FormatSpec("rodlab.compliance/2", "json", "compliance.schema.json", (".compliance.json",), "rod compliance"),
    FormatSpec("rodlab.fixture/1", "json", "fixture.schema.json", (".fixture.json",), "device fixture"),
    FormatSpec("rodlab.fixture/2", "json", "fixture2.schema.json", (),
               "device fixture with each pose's uncertainty"),
    FormatSpec("rodlab.device/1", "json", "device.schema.json", (".device.json",), "3-D measuring device"),
    FormatSpec("rodlab.device/2", "json", "device2.schema.json", (),
               "3-D measuring device with sensors that read the other way"),
    FormatSpec("rodlab.robot/2", "toml", "robot.schema.json", (".robot.toml",), "robot file"),
    FormatSpec("rodlab.calibration/1", "json", "calibration.schema.json", (".cal.json",), "calibration result"),
    FormatSpec("rodlab.diagnosis/1", "json", "diagnosis.schema.json", (".diagnosis.json",), "diagnosis report"),
    FormatSpec("rodlab.points_diagnosis/1", "json", "points_diagnosis.schema.json", (".points_diagnosis.json",),
               "diagnosis of instrument points"),
    FormatSpec("rodlab.rigplan/1", "toml", "rigplan.schema.json", (".plan.toml",), "rig plan"),
    FormatSpec("rodlab.rigprofile/1", "toml", "rigprofile.schema.json", (".profile.toml",), "rig profile"),
    FormatSpec("rodlab.rigprofile/2", "toml", "rigprofile2.schema.json", (".profile.toml",),
               "rig profile (several instruments)"),
    FormatSpec("rodlab.rig/1", "csv", "rig.table.json", (".rig.csv",), "rig recording"),
    FormatSpec("rodlab.campaign/1", "csv", "campaign.table.json", (".campaign.csv",), "calibration campaign"),
    FormatSpec("rodlab.points/1", "csv", "points.table.json", (".validation.csv", ".points.csv"),
               "instrument / validation points"),
    FormatSpec("rodlab.probe/1", "csv", "probe.table.json", (".probe.csv",), "device features probed at the "
               "clamping positions"),
    FormatSpec("rodlab.sockets/1", "csv", "sockets.table.json", (".sockets.csv",), "ball-in-socket / ball-bar readings"),
    FormatSpec("rodlab.blind_rig/1", "toml", "blind_rig.schema.json", (), "rig blind-case definitions"),
    FormatSpec("rodlab.blind_campaign/1", "toml", "blind_campaign.schema.json", (), "campaign blind-case definitions"),
)}
#: rodlab's own output records without a schema (nothing reads them back): only their JSON syntax is checked
UNCHECKED = {f"rodlab.{n}/1": "an output record of rodlab without a schema: only its JSON syntax is checked"
             for n in ("run", "sweep", "study", "joints", "mass", "comparison", "reference_designs",
                       "truth.campaign")}          # simulate-campaign's truth.json (a review)
#: format ids a file may state that are checked with another id's schema
ALIASES = {"rodlab.robot/1": "rodlab.robot/2", "rodlab.compliance/1": "rodlab.compliance/2",
           "rodlab.calibration/2": "rodlab.calibration/1"}


@dataclass(frozen=True)
class Problem:
    """One thing wrong with a file: where (line, key; each where known), what, and how to fix it."""

    path: str
    message: str
    line: int | None = None
    key: str | None = None
    fix: str = ""

    def __str__(self) -> str:
        where = ", ".join([self.path] + ([f"line {self.line}"] if self.line else [])
                          + ([f"key `{self.key}`"] if self.key else []))
        return f"{where}: {self.message}" + (f". Fix: {self.fix}" if self.fix else "")


@dataclass
class FileCheck:
    """The result of checking one file: its format (None if unknown), every problem found, and the warnings its
    reader gave (numbers no rod or robot has: a unit slip) on a file that passes."""

    path: str
    format: str | None
    problems: list = field(default_factory=list)
    note: str = ""
    warnings: list = field(default_factory=list)

    @property
    def ok(self) -> bool:
        return not self.problems


@lru_cache(maxsize=None)
def load_schema(format_id: str) -> dict:
    """The schema of ``format_id`` (a JSON Schema, or a table schema for CSV formats)."""
    spec = FORMATS[ALIASES.get(format_id, format_id)]
    return json.loads(resources.files("rodlab.schemas").joinpath(spec.schema_file).read_text(encoding="utf-8"))


def sniff_format(path: Path, text: str) -> str | None:
    """The format a file states (``format`` key or ``# format:`` comment), else the one its suffix suggests."""
    m = (re.search(r'"format"\s*:\s*"([^"]+)"', text) or re.search(r'(?m)^\s*format\s*=\s*"([^"]+)"', text)
         or re.search(r"(?m)^#\s*format:\s*(\S+)", text))
    if m:
        return m.group(1)
    name = path.name.lower()
    for spec in FORMATS.values():
        if any(name.endswith(s) for s in spec.suffixes):
            return spec.id
    return None


def _locate(text: str, kind: str, where: list) -> int | None:
    """The line of the key at path ``where`` (JSON: each key after the previous; TOML: the table header of the
    dotted path so far, array tables by index, else ``key =`` inside the current table); ``None`` if not
    found."""
    pos, table, names, parent = 0, None, [], 0
    for part in where:
        if isinstance(part, int):
            if kind == "toml" and table is not None:         # counted within the enclosing element
                hits = [parent + m.start() for m in
                        re.finditer(rf"(?m)^\s*\[\[\s*{re.escape(table)}\s*\]\]", text[parent:])]
                if part < len(hits):
                    pos = hits[part]
            elif kind == "json":                             # the element itself, not the array's first key
                pos = _json_element(text, pos, part)
            continue
        names.append(str(part))
        table = ".".join(names)
        parent = pos
        m = _find_key(text, kind, str(part), table, pos)
        if not m:
            return text.count("\n", 0, pos) + 1 if pos else None
        pos = m.start() + (len(m.group(0)) - len(m.group(0).lstrip()) if kind == "toml" else 0)
    return text.count("\n", 0, pos) + 1 if where else None


def _json_element(text: str, pos: int, index: int) -> int:
    """Where element ``index`` of the JSON array that is the value at ``pos`` (just after its key) begins; ``pos``
    where that value is no array or has no such element (a key repeated in every element of ``sensors`` had been
    located at the first element's line for each)."""
    colon = text.find(":", pos)
    start = colon + 1 + (len(text[colon + 1:]) - len(text[colon + 1:].lstrip())) if colon >= 0 else -1
    if start < 0 or not text.startswith("[", start):
        return pos
    depth, k, i, in_str = 0, 0, start, False
    while i < len(text):
        ch = text[i]
        if in_str:
            if ch == "\\":
                i += 1
            elif ch == '"':
                in_str = False
        elif depth == 1 and k == index and not ch.isspace() and ch not in ",]":
            return i                                         # the element's first character
        elif ch == '"':
            in_str = True
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
            if depth == 0:
                return pos
        elif ch == "," and depth == 1:
            k += 1
        i += 1
    return pos


def _find_key(text: str, kind: str, key: str, dotted: str, pos: int):
    """The match of ``key`` from ``pos``: JSON ``"key":``; TOML the header ``[dotted]`` / ``[[dotted]]``, else
    ``key =`` before the next table header (a same-named key of a later table is another key)."""
    if kind == "json":
        return re.compile(rf'"{re.escape(key)}"\s*:').search(text, pos)
    header = re.compile(rf"(?m)^\s*\[+\s*{re.escape(dotted)}\s*\]+").search(text, pos)
    if header:
        return header
    start = len(text) - len(text[pos:].lstrip())              # the current table's header, or its first line
    if text.startswith("[", start):
        start = text.find("\n", start) + 1 or len(text)
    nxt = re.compile(r"(?m)^[ \t]*\[").search(text, start)
    # a key with a dot in it is quoted in TOML ("tube.wall_mm" = ...)
    return re.compile(rf"(?m)^\s*([\"']?){re.escape(key)}\1\s*=").search(text, pos, nxt.start() if nxt else len(text))


def _dotted(where) -> str | None:
    out = ""
    for part in where:
        out += f"[{part + 1}]" if isinstance(part, int) else (("." if out else "") + str(part))
    return out or None


def _newer_version_hint(format_id: str | None, key: str) -> str:
    """For a key the file's format version lacks but a later version of the same format has: change the format
    line (e.g. ``[joints]`` in a ``rodlab.rod/1`` design belongs to ``rodlab.rod/2``)."""
    if not format_id or "/" not in format_id:
        return ""
    family = format_id.rsplit("/", 1)[0]
    for other in FORMATS:
        if other != format_id and other.rsplit("/", 1)[0] == family and FORMATS[other].kind != "csv":
            if key in _property_names(load_schema(other)) and key not in _property_names(load_schema(format_id)):
                change = (f"the format line to format = \"{other}\"" if FORMATS[other].kind == "toml" else
                          f"the file's format to \"{other}\"")
                return f"`{key}` belongs to {other}: change {change}"
    return ""


def _property_names(schema) -> set:
    """Every property name a schema declares, at any depth (a sensor's ``reading_sign`` of ``rodlab.device/2``
    sits in ``$defs``: a review found the /1 file told to remove it, which silently un-reversed the sensor)."""
    out: set = set()
    if isinstance(schema, dict):
        out |= set(schema.get("properties", {}) or {})
        for v in schema.values():
            out |= _property_names(v)
    elif isinstance(schema, list):
        for v in schema:
            out |= _property_names(v)
    return out


def _missing_key(err) -> str:
    """The key a ``required`` error misses."""
    missing = re.findall(r"'([^']+)' is a required property", err.message)
    return missing[0] if missing else "?"


def _misspelt(err) -> str | None:
    """The key present beside a ``required`` error's missing one that is its misspelling, or None."""
    inst, key = err.instance, _missing_key(err)
    present = [k for k in inst if k not in err.schema.get("properties", {})] if isinstance(inst, dict) else []
    return next((k for k in present if did_you_mean(k, [key])), None)


def _unknown_keys(err, format_id: str | None = None) -> list[tuple[str, str, list]]:
    """(message, fix, path) of each key an ``additionalProperties`` error finds unknown (a designer trial: the second
    unknown key of a table had shown only once the first was fixed)."""
    where, inst, schema = list(err.absolute_path), err.instance, err.schema
    allowed = sorted(schema.get("properties", {}))
    extra = [k for k in inst if k not in allowed] if isinstance(inst, dict) else []
    out = []
    for key in extra or ["?"]:
        hint = did_you_mean(key, allowed).strip() or _newer_version_hint(schema.get("$id") or format_id, key)
        out.append((f"unknown key `{key}`; allowed: {allowed}", hint or "remove it or check its spelling",
                    where + [key]))
    return out


def _explain(err) -> tuple[str, str, list]:
    """(message, fix, path) of one jsonschema error, in rodlab's words (an ``additionalProperties`` error's first
    unknown key: :func:`_unknown_keys` gives each)."""
    where = list(err.absolute_path)
    v, inst, schema = err.validator, err.instance, err.schema
    if v == "required":
        key, close = _missing_key(err), _misspelt(err)
        return (f"missing required key `{key}`", f"rename `{close}` to `{key}`" if close else
                f"add `{key}` (see docs/formats.md)", where + [key])
    if v == "additionalProperties":
        return _unknown_keys(err)[0]
    if v in ("const", "enum"):
        choices = [schema["const"]] if v == "const" else schema["enum"]
        hint = did_you_mean(inst, [str(c) for c in choices]).strip() if isinstance(inst, str) else ""
        return f"expected one of {choices}, got {inst!r}", hint or f"use one of {choices}", where
    if v == "type":
        kinds = schema["type"] if isinstance(schema["type"], list) else [schema["type"]]
        words = " or ".join(("an " if k[0] in "aeiou" else "a ") + k for k in kinds)
        return f"expected {words}, got {inst!r}", f"write {words}", where
    if v in ("minItems", "maxItems"):
        lo, hi = schema.get("minItems", 0), schema.get("maxItems")
        want = f"{lo}" if lo == hi else f"at least {lo}" if hi is None else f"{lo} to {hi}"
        return f"expected {want} items, got {len(inst)}", "give the number of entries the format states", where
    if v in ("minimum", "exclusiveMinimum", "maximum", "exclusiveMaximum"):
        op = {"minimum": ">=", "exclusiveMinimum": ">", "maximum": "<=", "exclusiveMaximum": "<"}[v]
        return f"expected a number {op} {schema[v]}, got {inst!r}", "correct the value (units are in the key)", where
    if v == "anyOf" and isinstance(inst, dict) and not where:
        return ("the design has no tube: neither a [tube] table nor both [pipe_I] and [pipe_II]",
                "give [tube], or both [pipe_I] and [pipe_II]", where)
    if v == "anyOf" and where and where[0] == "tolerances":
        return (f"expected one standard deviation: a number >= 0 in the key's unit, or a percentage such as \"5%\", "
                f"got {inst!r}", 'write e.g. 0.05 or "5%"', where)
    return err.message, "", where


@lru_cache(maxsize=None)
def _validator(format_id: str):
    from jsonschema import Draft202012Validator
    return Draft202012Validator(load_schema(format_id))


def data_problems(data, format_id: str, path: str = "", text: str = "", kind: str = "json") -> list[Problem]:
    """Every problem of the parsed ``data`` against the JSON Schema of ``format_id``."""
    validator = _validator(ALIASES.get(format_id, format_id))
    out = []
    for err in validator.iter_errors(data):
        for message, fix, where in (_unknown_keys(err, format_id) if err.validator == "additionalProperties"
                                    else [_explain(err)]):
            located = where                                                  # a missing key: its table's line,
            if err.validator == "required":                                  # or the line of its misspelling
                located = where[:-1] + ([m] if (m := _misspelt(err)) else [])
            out.append(Problem(path, message, _locate(text, kind, located) if text else None, _dotted(where), fix))
    return sorted(out, key=lambda p: (p.line or 0, p.key or ""))


def _parse(p: Path, text: str, kind: str):
    """(data, problem) of a JSON or TOML text."""
    try:
        return (json.loads(text) if kind == "json" else tomllib.loads(text)), None
    except json.JSONDecodeError as e:
        return None, Problem(str(p), f"not valid JSON: {e.msg} (column {e.colno})", e.lineno, None,
                             "correct the syntax at that place")
    except tomllib.TOMLDecodeError as e:
        message, line = toml_problem(e, text)
        return None, Problem(str(p), message, line, None, "correct the syntax at that place")


def check_file(path, format_id: str | None = None) -> FileCheck:
    """Every schema problem of the file at ``path`` (its format sniffed unless ``format_id`` is given)."""
    from .schema_table import table_problems  # cycle: schema_table imports Problem from here

    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")   # a byte-order mark is not text
    except FileNotFoundError:
        return FileCheck(str(p), None, [Problem(str(p), "file not found", fix="check the path")])
    except (OSError, UnicodeDecodeError) as e:
        return FileCheck(str(p), None, [Problem(str(p), f"cannot be read as UTF-8 text: {e}",
                                                fix="give a text file rodlab writes or reads")])
    fid = format_id or sniff_format(p, text)
    if fid in UNCHECKED and format_id is None:
        _, problem = _parse(p, text, "json")
        return FileCheck(str(p), fid, [problem] if problem else [], note=UNCHECKED[fid])
    if fid is None or ALIASES.get(fid, fid) not in FORMATS:
        known = sorted(FORMATS) + sorted(ALIASES)
        return FileCheck(str(p), fid, [Problem(str(p), f"unknown format {fid!r}" if fid else
                                               "cannot tell the format (no `format` key, no known suffix)",
                                               key="format",
                                               fix=(did_you_mean(fid, known).strip() if fid else "") or
                                               f"state one of {known} with --format")])
    spec = FORMATS[ALIASES.get(fid, fid)]
    if spec.kind == "csv":
        return FileCheck(str(p), fid, table_problems(text, load_schema(fid), str(p)))
    data, problem = _parse(p, text, spec.kind)
    if problem is not None:
        return FileCheck(str(p), fid, [problem])
    return FileCheck(str(p), fid, data_problems(data, fid, str(p), text, spec.kind))


def require_schema(data, format_id: str, path, text: str, error_cls, kind: str = "json") -> None:
    """Raise ``error_cls`` (a :class:`~rodlab.core.errors.LocatedError`) listing every problem of ``data`` against
    the schema of ``format_id``, located at the first; nothing if there is none. The readers call it first."""
    problems = data_problems(data, format_id, str(path) if path is not None else "", text or "", kind)
    if not problems:
        return
    first = problems[0]
    more = "".join(f"; {p.message} (" + ", ".join(([f"line {p.line}"] if p.line else []) +
                                                  ([f"key `{p.key}`"] if p.key else [])) + ")"
                   for p in problems[1:])
    fix = f". Fix: {first.fix}" if first.fix else ""
    raise error_cls(f"{first.message}{fix}{more}", path=path, line=first.line, key=first.key)


def read_toml_checked(path, format_id: str, error_cls) -> tuple[dict, str]:
    """Read a TOML file of ``format_id`` and check it against its schema: (table, text). Raises ``error_cls``
    naming the file (unreadable, not TOML: with the line) or every schema problem at once."""
    data, text = read_toml(path, error_cls)
    require_schema(data, format_id, path, text, error_cls, kind="toml")
    return data, text

