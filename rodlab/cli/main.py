"""``rodlab`` entry point: argparse sub-commands, logging set-up, and error reporting.

Every input error (:class:`~rodlab.errors.RodlabError`) and OS error is printed as one clear
line on stderr with exit code 2; never a traceback. ``--debug`` shows tracebacks.
"""
from __future__ import annotations

import argparse
import logging
import sys

from .. import __version__, progress
from ..errors import RodlabError
from . import cmd_calibrate, cmd_demo, cmd_design, cmd_diagnose, cmd_fea, cmd_geometry, cmd_rig, cmd_study, cmd_sweep

__all__ = ["build_parser", "main"]

#: Modules that add sub-commands: each has ``register(subparsers)``.
_COMMAND_MODULES = [cmd_demo, cmd_design, cmd_geometry, cmd_fea, cmd_sweep, cmd_study, cmd_rig, cmd_calibrate,
                    cmd_diagnose]


def _global_options(parser: argparse.ArgumentParser, suppress: bool) -> None:
    """-v, -q, --debug: accepted before the sub-command and after it (``rodlab fea ... --debug``)."""
    kw = {"default": argparse.SUPPRESS} if suppress else {}
    parser.add_argument("-v", "--verbose", action="count", help="more log output (-vv for debug)",
                        **(kw or {"default": 0}))
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bars", **kw)
    parser.add_argument("--debug", action="store_true", help="show tracebacks on errors", **kw)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="rodlab",
        description="Design, simulate, measure and use long measuring rods for on-site robot calibration "
                    "(MultiCal).")
    parser.add_argument("--version", action="version", version=f"rodlab {__version__}")
    _global_options(parser, suppress=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for mod in _COMMAND_MODULES:
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


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    level = [logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)]
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")
    progress.configure(sys.stderr.isatty() and not args.quiet)
    if not getattr(args, "func", None):
        parser.print_help()
        return 1
    try:
        return int(args.func(args) or 0)
    except RodlabError as e:
        if args.debug:
            raise
        print(f"rodlab {args.command}: error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:                 # output piped into `head` and closed: not an error
        return 0
    except OSError as e:
        if args.debug:
            raise
        where = f" {e.filename}" if getattr(e, "filename", None) else ""
        print(f"rodlab {args.command}: error:{where}: {e.strerror or e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"rodlab {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
