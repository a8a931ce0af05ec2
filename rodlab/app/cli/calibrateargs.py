"""The options ``rodlab calibrate`` and ``rodlab compare`` share, and the ``--pin`` parser."""
from __future__ import annotations

from ...core.errors import RodlabError
from ...core.units import DEVICE_NOISE_MM, TRACKER_NOISE_MM
from .argtypes import pos_float
from .columnsargs import add_columns_checked
from .reporting import add_report_option
from .robotargs import add_robot_options, robot_help

__all__ = ["add_identify_options", "parse_pins", "pins_from_args"]


def add_identify_options(p) -> None:
    """The options calibrate and compare share: robot, validation points, pins, loss, noise, report, strictness."""
    add_robot_options(p, default=None, help=robot_help() + "; default tx90 (the paper's robot) for a campaign, while "
                                                         "instrument points and socket readings must name theirs")
    p.add_argument("--validate", default=None,
                   help="validation points (*.validation.csv) for the paper's statistics; with --sockets, other "
                        "socket readings (*.sockets.csv) to check the model's consistency and distortion on")
    p.add_argument("--pin", action="append", default=[], metavar="NAME=VALUE",
                   help="hold a parameter at a value (contract units), e.g. c_6=0 (repeatable)")
    p.add_argument("--free", action="append", default=[], metavar="NAME",
                   help="free a parameter the defaults hold, e.g. fixture_2_x (repeatable)")
    p.add_argument("--robust", action="store_true", help="soft-L1 loss (gross alignment errors lose weight)")
    p.add_argument("--noise-um", type=pos_float, default=None,
                   help="the measuring instrument's noise per coordinate [um], 1 sigma, that the trust verdict "
                        f"judges the residuals against (default: {DEVICE_NOISE_MM * 1e3:g} um for a MultiCal "
                        f"campaign; for --points the file's sigma_*_mm columns, else {TRACKER_NOISE_MM * 1e3:g} um: a laser "
                        f"tracker at a few metres; for --sockets the file's seat_sigma_mm / length_sigma_mm). Given, "
                        f"it replaces the per-point columns or the file's sigma")
    p.add_argument("--noise-checked", action="store_true",
                   help="the --noise-um given is this device's, as a repeatability test shows it: a MultiCal campaign "
                        "whose residuals pass only at more than 5x a MultiCal device's noise is otherwise not trusted "
                        "(such scatter is the files': a reading column's sign, another campaign's fixture)")
    add_columns_checked(p)
    add_report_option(p)
    p.add_argument("--strict", action="store_true",
                   help="refuse a data set that cannot identify every parameter (naming them and the remedy) "
                        "instead of holding those at nominal or at their start values (regularised)")
    p.add_argument("--fix-unidentifiable", action="store_true",
                   help="hold the parameters these data cannot identify at nominal (and report them); the default "
                        "unless --strict, kept for scripts")


def pins_from_args(args, n: int) -> dict:
    """``--pin`` values, and with ``--kinematic-only`` every joint compliance at 0."""
    pins = parse_pins(args.pin)
    if getattr(args, "kinematic_only", False):
        pins.update({f"c_{i}": 0.0 for i in range(2, n + 1)})
    return pins


def parse_pins(items) -> dict:
    out = {}
    for it in items:
        k, eq, v = it.partition("=")
        try:
            out[k.strip()] = float(v)
        except ValueError:
            raise RodlabError(f"--pin {it!r}: expected NAME=VALUE") from None
        if not eq:
            raise RodlabError(f"--pin {it!r}: expected NAME=VALUE")
    return out
