"""``--report [HTML]`` on every command that writes results: one self-contained page of what it just wrote."""
from __future__ import annotations

import argparse
import shlex
from pathlib import Path

__all__ = ["add_report_option", "write_command_report", "default_folder", "png_file", "png_folder", "PNG_CONVENTION"]

#: the one --png convention of every command (docs/cli.md shows it in each command's help)
PNG_CONVENTION = "a folder (each figure under its own name); a command that draws one figure also takes FILE.png"


def png_file(spec: str | None, name: str) -> Path | None:
    """--png of a command that draws one figure: ``FILE.png`` itself, else a folder that gets ``name``."""
    if not spec:
        return None
    p = Path(spec)
    return p if p.suffix.lower() == ".png" else p / name


def png_folder(spec: str) -> str:
    """argparse type of --png for a command that draws several figures: a folder, never ``FILE.png``."""
    if Path(spec).suffix.lower() == ".png":
        raise argparse.ArgumentTypeError(f"{spec!r}: this command draws several figures: give a folder, e.g. "
                                         f"{str(Path(spec).with_suffix(''))!r}")
    return spec


def add_report_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--report", nargs="?", const="", default=None, metavar="HTML",
                   help="also write a self-contained HTML report of this run (default: COMMAND.report.html beside "
                        "the results); `rodlab report DIR` renders a whole folder")


def write_command_report(args: argparse.Namespace, written: list, folder: Path) -> Path | None:
    """Write the report of ``written`` (paths of results and PNGs, or in-memory report Sources) when
    ``--report`` was given; ``folder`` is where it goes by default."""
    if getattr(args, "report", None) is None:
        return None
    from ..report import Source, classify, write_sources_report
    from ..report.html import esc
    sources, figures = [], []
    for item in written:
        if isinstance(item, Source):
            sources.append(item)
        elif Path(item).suffix == ".png":
            figures.append(Path(item))
        elif (src := classify(Path(item))) is not None:
            sources.append(src)
    command = " ".join(str(c) for c in (args.command, getattr(args, "rig_command", None)) if c)
    out = Path(args.report) if args.report else Path(folder) / f"{command.replace(' ', '-')}.report.html"
    line = "rodlab " + " ".join(shlex.quote(a) for a in getattr(args, "argv", []) or [])
    path = write_sources_report(out, sources, figures, f"rodlab {command}", f"Command: <code>{esc(line)}</code>")
    print(f"wrote {path}")
    return path


def default_folder(args: argparse.Namespace) -> Path:
    """Where ``--report`` goes by default when the results are a JSON and / or a figure folder: beside the
    JSON, else in the figure folder, else here."""
    if getattr(args, "json", None):
        return Path(args.json).parent
    return Path(args.png) if getattr(args, "png", None) else Path(".")
