"""Robot descriptions rodlab reads, one reader per file kind (the registry), and the built-in robots.

Adding a format is one reader module ``calibrate/robot_NAME.py`` and its test: the module declares its
``ROBOT_FORMAT`` (a :class:`RobotFormat`: the suffix, the reader, what the format is in a help text, and the name
``rodlab validate`` gives a file of it that has no JSON schema), and :func:`discover` (run on import) puts it in
:data:`ROBOT_READERS` (suffix -> format, in the order of the module names). A reader takes the path and the
chain's ``base_link`` / ``tip_link`` (only URDF uses them) and returns a :class:`Robot`. The ``--robot`` help of
every command, ``rodlab validate --format`` and the table of docs/formats.md are generated from it.
Built-in robots are the files in ``calibrate/robots`` (each names its source), by file stem.
"""
from __future__ import annotations

import logging
from importlib import resources
from pathlib import Path

from rodlab.core.errors import did_you_mean
from rodlab.core.registry import package_modules

from .errors import CalibrationError
from .robot import Robot
from .robot_reader import RobotFormat

__all__ = ["ROBOT_READERS", "RobotFormat", "discover", "robot_formats_help", "robot_formats_markdown", "read_robot",
           "resolve_robot", "robot_path", "builtin_robots"]

log = logging.getLogger(__name__)


#: file suffix -> its :class:`RobotFormat` (called as reader(path, base_link, tip_link)); filled by :func:`discover`
ROBOT_READERS: dict[str, RobotFormat] = {}


def discover() -> dict[str, RobotFormat]:
    """Find the robot formats: the ``ROBOT_FORMAT`` of every ``robot_*`` module of this package (a folder added to
    its ``__path__`` too), by module name; refill :data:`ROBOT_READERS` in place and return it.
    :class:`CalibrationError` naming both modules when two read the same suffix."""
    found, where = {}, {}
    for module in sorted(package_modules(__package__, "robot_"), key=lambda m: m.__name__.rsplit(".", 1)[1]):
        fmt = getattr(module, "ROBOT_FORMAT", None)
        if fmt is None:
            continue
        if not (fmt.suffix.startswith(".") and fmt.suffix == fmt.suffix.lower()):
            raise CalibrationError(f"{module.__name__}: ROBOT_FORMAT needs a lower-case suffix with its dot "
                                   f"(e.g. '.urdf'), got {fmt.suffix!r}")
        if fmt.suffix in found:
            raise CalibrationError(f"{where[fmt.suffix]} and {module.__name__} both read {fmt.suffix} files; keep one")
        found[fmt.suffix], where[fmt.suffix] = fmt, module.__name__
    ROBOT_READERS.clear()
    ROBOT_READERS.update(found)
    return ROBOT_READERS


def robot_formats_help() -> str:
    """``built-in robot (tx90, ...), a robot TOML file (...) or a URDF (...)``: the built-in robots and the
    registered formats, for the ``--robot`` help texts."""
    kinds = [f.describes for f in ROBOT_READERS.values()]
    files = ", ".join(kinds[:-1]) + " or " + kinds[-1] if len(kinds) > 1 else kinds[0]
    return f"built-in robot ({', '.join(builtin_robots())}), {files}"


def robot_formats_markdown() -> str:
    """The robot file formats and the built-in robots as the Markdown table of docs/formats.md (generated:
    ``scripts/gen_cli_docs.py``)."""
    rows = ["| suffix | robot file | `rodlab validate` checks it as |", "|---|---|---|"]
    for suffix, f in ROBOT_READERS.items():
        rows.append(f"| `{suffix}` | {f.describes} | "
                    + (f"`{f.format_id}` (its reader's rules)" if f.format_id else "its `format` key and schema") + " |")
    robots = ", ".join(f"`{name}` ({p.suffix.lstrip('.').upper()})" for name, p in builtin_robots().items())
    return "\n".join(rows) + f"\n\nBuilt in (`--robot NAME`, the files in `calibrate/robots/`): {robots}."


def read_robot(path, base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """Read a robot file of any registered kind, chosen by its suffix (a file without one is sniffed)."""
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix not in ROBOT_READERS and p.is_file():
        head = p.read_text(encoding="utf-8", errors="replace")[:2000].lstrip()
        suffix = ".urdf" if head.startswith("<") else ".toml"
    if suffix not in ROBOT_READERS:
        raise CalibrationError(f"unknown robot file kind {p.suffix!r}; rodlab reads {sorted(ROBOT_READERS)}", path=p)
    return ROBOT_READERS[suffix](p, base_link, tip_link)


def builtin_robots() -> dict[str, Path]:
    """Built-in robot name -> its file (TOML before URDF when both exist)."""
    folder = resources.files("rodlab.calibrate") / "robots"
    out = {}
    for f in sorted(folder.iterdir(), key=lambda f: (Path(str(f)).suffix != ".toml", str(f))):
        p = Path(str(f))
        if p.suffix in ROBOT_READERS:
            out.setdefault(p.stem.lower(), p)
    return out


def resolve_robot(spec: str | Path, base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """A robot file path (any registered kind), or a built-in name (``tx90``, case-blind).

    A name is a file only when it is a file: a folder named like a built-in (``ur5/``, made by ``--json
    ur5/cal.json``) does not hide the built-in robot; the log says which was taken when both exist.
    """
    return read_robot(robot_path(spec), base_link, tip_link)


def robot_path(spec: str | Path) -> Path:
    """The file a robot spec names: an existing file, else a built-in robot's file, else a path with a robot
    suffix (its reader says "file not found"); a folder or an unknown name is refused with the built-ins."""
    p = Path(spec)
    names = builtin_robots()
    key = str(spec).strip().lower()
    if p.is_file():
        if key in names:
            log.warning("%s: the file here, not the built-in robot %s (give another path to use the built-in)",
                        spec, key)
        return p
    if key in names:
        if p.exists():
            log.warning("%s: the built-in robot %s, not the folder %s/ here (a folder is not a robot file)",
                        spec, key, spec)
        return names[key]
    if p.is_dir():
        raise CalibrationError(f"this is a folder, not a robot file; give a robot file (.toml, .urdf) or a built-in "
                               f"robot: {sorted(names)}.", path=spec)
    if p.suffix.lower() in ROBOT_READERS:
        return p
    raise CalibrationError(f"no such robot file or built-in robot; built-ins: {sorted(names)}."
                           + did_you_mean(str(spec), names), path=spec)


discover()
