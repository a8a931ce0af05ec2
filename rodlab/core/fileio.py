"""File helpers: atomic writes and content hashes (nothing already recorded is ever lost)."""
from __future__ import annotations

import errno
import hashlib
import io
import json
import math
import os
import re
import sys
import tempfile
from contextvars import ContextVar
from pathlib import Path

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["write_generated", "atomic_write_text", "atomic_write_bytes", "atomic_write_json", "dumps_compact", "json_safe",
           "sha256_file", "read_text_checked", "read_toml", "read_json", "separator_problem", "toml_problem"]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def atomic_write_bytes(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically: temp file in the same folder, fsync, rename.

    A crash leaves either the old file or the new one, never a torn file. A symbolic link is followed (the file
    it points to is replaced, the link kept); a device or pipe (``-o /dev/null``, ``/dev/stdout``) is written
    into as it is: renamed over, it would be replaced by a regular file.
    """
    p = Path(path)
    if p.is_dir():                       # else the error would name the temporary file, not the user's path
        raise IsADirectoryError(errno.EISDIR, "this is a folder", str(p))
    if p.is_symlink():
        p = p.resolve()
    if p.exists() and not p.is_file():
        with open(p, "wb") as fh:
            fh.write(data)
        return Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    except OSError as e:                                       # name the user's path, never the temporary file
        raise type(e)(e.errno, e.strerror, str(p)) from e
    try:
        os.fchmod(fd, 0o666 & ~_umask())       # mkstemp makes 0600; give the file normal permissions
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, p)
    except BaseException as e:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(e, OSError) and e.filename == tmp:     # name the user's path, never the temporary file
            raise type(e)(e.errno, e.strerror, str(p)) from e
        raise
    return p


#: where :func:`atomic_write_figure` hands its figures instead of rendering them (an object with
#: ``submit(path, fig, dpi, savefig_kw) -> bool``): set inside :func:`rodlab.core.figures_bg.background_figures`
FIGURE_SINK: ContextVar = ContextVar("rodlab_figure_sink", default=None)


def atomic_write_figure(path: str | Path, fig, dpi: int = 120, **savefig_kw) -> Path:
    """Render a matplotlib figure to PNG in memory, close it, and write the file atomically (never a partial
    image). Inside :func:`rodlab.core.figures_bg.background_figures` the figure is handed to its worker process
    and the file appears later (readers wait with :func:`~rodlab.core.figures_bg.wait_for_figure`)."""
    bg = FIGURE_SINK.get()
    if bg is not None and bg.submit(path, fig, dpi, savefig_kw):
        return Path(path)
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, dpi=dpi, **savefig_kw)
    plt.close(fig)
    return atomic_write_bytes(path, buf.getvalue())


def atomic_write_text(path: str | Path, text: str) -> Path:
    """Atomic UTF-8 text write (see :func:`atomic_write_bytes`)."""
    return atomic_write_bytes(path, text.encode("utf-8"))


def json_safe(obj):
    """Replace non-finite floats by ``None`` (JSON ``null``) and NumPy scalars/arrays by Python values."""
    if isinstance(obj, dict):
        return {str(k): json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [json_safe(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return json_safe(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def dumps_compact(obj, indent: int = 1) -> str:
    """JSON with ``indent`` but innermost lists of scalars kept on one line (matrices stay legible)."""
    text = json.dumps(obj, indent=indent, allow_nan=False)
    return re.sub(r"\[\s*([^\[\]{}]*?)\s*\]", lambda m: "[" + ", ".join(
        part.strip() for part in m.group(1).split(",")) + "]" if m.group(1).strip() else "[]", text)


def atomic_write_json(path: str | Path, obj, indent: int = 1) -> Path:
    """Atomic JSON write (NaN/inf refused) with a trailing newline; matrices on one line per row."""
    return atomic_write_text(path, dumps_compact(obj, indent) + "\n")


def read_text_checked(path, error_cls) -> str:
    """A file's UTF-8 text (a leading byte-order mark dropped), or ``error_cls`` (a FormatError) naming the file:
    not found, unreadable, not UTF-8 (with the line of the first bad byte)."""
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError as e:
        raise error_cls("file not found", path=p) from e
    except OSError as e:
        raise error_cls(f"cannot read: {e.strerror}", path=p) from e
    try:
        return raw.decode("utf-8-sig")          # a byte-order mark (Excel, Notepad) is not text
    except UnicodeDecodeError as e:
        raise error_cls(f"not UTF-8 text ({e.reason})", path=p, line=raw[:e.start].count(b"\n") + 1) from e


def separator_problem(header_line: str) -> str | None:
    """What is wrong with a CSV header line written with another separator than the comma (a spreadsheet in a
    decimal-comma locale writes ``;``, a logger often a tab), or None: rodlab's tables are comma-separated."""
    if "," in header_line:
        return None
    for sep, name in ((";", "semicolons"), ("\t", "tabs")):
        if sep in header_line:
            return (f"the header is separated by {name}, not commas: rodlab's CSV files are comma-separated with a "
                    "decimal point; export the file again as CSV with ',' between cells (or replace the "
                    f"{name}{' and decimal commas' if sep == ';' else ''})")
    return None


def read_toml(path, error_cls) -> tuple[dict, str]:
    """A TOML file's table and text, or ``error_cls`` naming the file: unreadable (:func:`read_text_checked`)
    or not valid TOML (with the line the parser names)."""
    p = Path(path)
    text = read_text_checked(p, error_cls)
    try:
        return tomllib.loads(text), text
    except tomllib.TOMLDecodeError as e:
        message, line = toml_problem(e, text)
        raise error_cls(f"{message}{_kind_hint(text, 'TOML')}", path=p, line=line) from e


def toml_problem(e: Exception, text: str) -> tuple[str, int | None]:
    """(what is wrong, its line) from a TOML parser's error ``e`` on ``text``: its message, and for a key or table
    given twice (the parser says only "Cannot overwrite a value") the key at that line and the fix."""
    m = re.search(r"line (\d+)", str(e))
    line = int(m.group(1)) if m else None
    message = f"not valid TOML: {e}"
    lines = text.splitlines()
    if line and 0 < line <= len(lines) and re.search(r"overwrite|declare|twice|already", str(e), re.I):
        here = lines[line - 1].split("#", 1)[0].strip()
        table = re.fullmatch(r"\[\s*([^\[\]]+?)\s*\]", here)
        key = re.match(r"([A-Za-z0-9_.\"' -]+?)\s*=", here)
        if table:
            message += f": the table [{table.group(1)}] is declared a second time at line {line}; merge the two"
        elif key:
            message += (f": {key.group(1).strip()!r} is given a second time in its table at line {line}; keep one "
                        "of the two")
    return message, line


def read_json(path, error_cls) -> tuple[object, str]:
    """A JSON file's data and text, or ``error_cls`` naming the file: unreadable (:func:`read_text_checked`) or
    not valid JSON (with the line and column the parser names)."""
    p = Path(path)
    text = read_text_checked(p, error_cls)
    try:
        return json.loads(text), text
    except json.JSONDecodeError as e:
        raise error_cls(f"not valid JSON: {e.msg} (column {e.colno}){_kind_hint(text, 'JSON')}", path=p,
                        line=e.lineno) from e


def _kind_hint(text: str, expected: str) -> str:
    """What kind of file ``text`` is when it is plainly not the ``expected`` one (TOML or JSON): a JSON file (a
    compliance, fixture or result file), a rig recording or another CSV, so an error says which file was given."""
    head = text.lstrip()
    if expected != "JSON" and head.startswith("{"):
        return "; this is a JSON file (a compliance, fixture or result file?), not the TOML file expected here"
    if "# format: rodlab.rig/" in text[:400]:
        return f"; this is a rig recording (*.rig.csv), not the {expected} file expected here"
    first = next((ln for ln in head.splitlines() if ln.strip() and not ln.startswith("#")), "")
    if first.count(",") >= 3 and "=" not in first and not first.startswith(("{", "[")):
        return f"; this looks like a CSV table, not the {expected} file expected here"
    if expected == "JSON" and re.match(r"(format|name)\s*=", first):
        return "; this is a TOML file (a design or robot file?), not the JSON file expected here"
    return ""


def write_generated(path: str | Path, text: str, check: bool = False) -> int:
    """For the scripts that generate docs: write ``text`` to ``path`` atomically, or with ``check`` only
    compare (exit status 0 when the file is current, 1 when it must be regenerated)."""
    p = Path(path)
    if check:
        return 0 if p.exists() and p.read_text(encoding="utf-8") == text else 1
    atomic_write_text(p, text)
    return 0


def sha256_file(path: str | Path) -> str:
    """Hex SHA-256 of a file's bytes."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()
