"""``rodlab`` entry point: argparse sub-commands, logging set-up, and error reporting.

Every input error (:class:`~rodlab.core.errors.RodlabError`) and OS error is printed as one clear
line on stderr with exit code 2; never a traceback. ``--debug`` shows tracebacks.
"""
from __future__ import annotations

import argparse
import errno
import gc
import importlib
import logging
import pkgutil
import re
import sys
from pathlib import Path

from ... import __version__
from ...core import progress
from ...core.errors import RodlabError, VerdictError, did_you_mean

__all__ = ["build_parser", "main", "console", "command_modules", "COMMAND_ORDER"]

#: the order of ``rodlab --help``. Every ``cmd_*.py`` module of this package that has ``register(subparsers)``
#: adds its sub-command; one not listed here is found all the same and listed after these, by name (a new
#: sub-command is its module and its test; list it here only to place it)
COMMAND_ORDER = ("demo", "report", "info", "compliance", "cad", "mesh", "fea", "sweep", "study", "rig", "calibrate",
                 "compare", "simulate_campaign", "plan", "fixture", "diagnose", "update", "export", "correct",
                 "validate", "view")


def command_modules() -> list:
    """The modules that add sub-commands (each has ``register(subparsers)``), in the order of the help."""
    package = sys.modules[__package__]
    found = sorted(m.name[len("cmd_"):] for m in pkgutil.iter_modules(package.__path__) if m.name.startswith("cmd_"))
    names = [n for n in COMMAND_ORDER if n in found] + [n for n in found if n not in COMMAND_ORDER]
    modules = [importlib.import_module(f"{__package__}.cmd_{n}") for n in names]
    return [m for m in modules if callable(getattr(m, "register", None))]


def _global_options(parser: argparse.ArgumentParser, suppress: bool) -> None:
    """-v, -q, --debug: accepted before the sub-command and after it (``rodlab fea ... --debug``)."""
    kw = {"default": argparse.SUPPRESS} if suppress else {}
    parser.add_argument("-v", "--verbose", action="count", help="more log output (-vv for debug)",
                        **(kw or {"default": 0}))
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bars", **kw)
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors", **kw)


class RodlabParser(argparse.ArgumentParser):
    """argparse with one-line errors (exit 2): the error, the nearest choice for a misspelt one, and where the
    help is; the sub-command parsers inherit it."""

    def error(self, message: str):
        m = re.match(r"argument (\S+): invalid choice: '?([^' ]*)'? \(choose from (.*)\)", message)
        if m:
            choices = re.findall(r"'([^']*)'", m.group(3)) or [c.strip() for c in m.group(3).split(",")]
            message += did_you_mean(m.group(2), choices)
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def _named_command_module(argv: list[str] | None):
    """The module of the sub-command ``argv`` names (its first word that is not an option), if there is one:
    only it need be imported and registered (the others' imports cost ~0.3 s of every command's start)."""
    args = list(sys.argv[1:] if argv is None else argv)
    first = next((i for i, a in enumerate(args) if not a.startswith("-")), None)
    if first is None or any(a in ("-h", "--help", "--version") for a in args[:first]):
        return None                         # `rodlab -h fea` is the help of rodlab: every command
    words = args[first:]
    name = f"cmd_{words[0].replace('-', '_')}"
    package = sys.modules[__package__]
    if not any(m.name == name for m in pkgutil.iter_modules(package.__path__)):
        return None                         # a misspelt command: the full parser names the nearest one
    module = importlib.import_module(f"{__package__}.{name}")
    return module if callable(getattr(module, "register", None)) else None


def build_parser(argv: list[str] | None = None, *, every_command: bool = True) -> argparse.ArgumentParser:
    """The parser of every sub-command, or with ``every_command=False`` only of the one ``argv`` names (when it
    names one: ``rodlab fea ...`` imports and registers ``cmd_fea`` only)."""
    parser = RodlabParser(
        prog="rodlab",
        description="Design, simulate, measure and use long measuring rods for on-site robot calibration "
                    "(MultiCal).")
    parser.add_argument("--version", action="version", version=f"rodlab {__version__}")
    _global_options(parser, suppress=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    named = None if every_command else _named_command_module(argv)
    for mod in [named] if named is not None else command_modules():
        mod.register(sub)
    _add_global_options_below(parser)
    return parser


def _add_global_options_below(parser: argparse.ArgumentParser) -> None:
    """Every sub-command (and sub-sub-command, ``rodlab rig simulate``) accepts -v, -q and --debug too."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sp in set(action.choices.values()):
                if "--debug" not in sp._option_string_actions:
                    _global_options(sp, suppress=True)
                _add_global_options_below(sp)


def console() -> int:
    """The ``rodlab`` console script (and ``python -m rodlab``): :func:`main`, then every object left is moved
    out of the garbage collector's reach (``gc.freeze``): the process is about to exit, and the interpreter's
    final collection would only walk them (~30 ms after a solid FEA). NumPy sub-packages no command needs load on
    first use (:mod:`.startup`). In-process callers use :func:`main`."""
    from .startup import defer_numpy_submodules  # cli start-up: only the console script defers them
    defer_numpy_submodules()
    code = main()
    gc.freeze()
    return code


class _UserFormatter(logging.Formatter):
    """Log lines as the commands' own messages read (``warning: ...``); ``-v`` adds the level and the logger."""

    def format(self, record: logging.LogRecord) -> str:
        return f"{record.levelname.lower()}: {record.getMessage()}"


def main(argv: list[str] | None = None) -> int:
    parser = build_parser(argv, every_command=False)
    args = parser.parse_args(argv)
    args.argv = list(sys.argv[1:] if argv is None else argv)
    level = [logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)]
    handler = logging.StreamHandler()
    handler.setFormatter(logging.Formatter("%(levelname)s %(name)s: %(message)s") if args.verbose else _UserFormatter())
    logging.basicConfig(level=level, handlers=[handler])
    progress.configure(sys.stderr.isatty() and not args.quiet)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    name = " ".join(filter(None, (args.command, getattr(args, "rig_command", None))))
    try:
        _check_outputs(args)
        return int(args.func(args) or 0)
    except RodlabError as e:
        if args.debug:
            raise
        verdict = isinstance(e, VerdictError)
        print(f"rodlab {name}: {'refused' if verdict else 'error'}: {e}", file=sys.stderr)
        return 3 if verdict else 2
    except BrokenPipeError:                 # output piped into `head` and closed: not an error
        return 0
    except OSError as e:
        if args.debug:
            raise
        print(f"rodlab {name}: error: {_os_error_text(e)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"rodlab {name}: interrupted", file=sys.stderr)
        return 130


#: argparse destinations that name something the command writes
_OUTPUT_DESTS = ("output", "json", "png", "export", "joints_out", "report", "fields")
#: of those, the ones that are always a file (``-o`` and ``--png`` may name folders)
_FILE_DESTS = ("json", "report")


def _check_outputs(args: argparse.Namespace) -> None:
    """Before any work: two outputs must not share a path, and no part of an output's folder may be a file
    (else the first output would be written and the second fail, leaving a partial result)."""
    seen: dict[Path, str] = {}
    for dest in _OUTPUT_DESTS:
        value = getattr(args, dest, None)
        if not isinstance(value, str) or not value:
            continue
        option = "--" + dest.replace("_", "-")
        path = Path(value).expanduser().absolute()
        if path in seen:
            raise RodlabError(f"{option} {value}: the same path as {seen[path]}; give each output its own path")
        seen[path] = option
        if dest in _FILE_DESTS and path.is_dir():
            raise RodlabError(f"{option} {value}: this is a folder; give a file name (e.g. {Path(value) / 'x'}"
                              f"{'.report.html' if dest == 'report' else '.json'})")
        for parent in path.parents:
            if parent.exists():
                if not parent.is_dir():
                    raise RodlabError(f"{option} {value}: {parent} is a file, not a folder; choose another "
                                      f"output path")
                break


#: errno -> what it means for a user's paths, and the fix
_OS_ADVICE = {
    errno.EEXIST: "a file is in the way where a folder is needed; choose another output path or move the file",
    errno.ENOTDIR: "a part of the path is a file, not a folder; choose another output path",
    errno.EISDIR: "this is a folder; give a file name",
    errno.ENOENT: "no such file or folder; check the path",
    errno.EACCES: "permission denied; choose a folder you can write to",
    errno.EROFS: "the file system is read-only; choose another output path",
    errno.ENOSPC: "the disk is full; free space or write elsewhere (nothing partial was kept)",
    errno.ENAMETOOLONG: "a file name longer than the file system allows (255 bytes per name); give a shorter path",
}


def _os_error_text(e: OSError) -> str:
    """``PATH: what went wrong; the fix`` for an operating-system error."""
    where = f"{e.filename}: " if getattr(e, "filename", None) else ""
    return where + _OS_ADVICE.get(e.errno, str(e.strerror or e))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
