"""What ``rodlab calibrate`` (campaign, points, sockets) prints and writes of an identification."""
from __future__ import annotations

import sys

from rodlab.calibrate import write_result
from rodlab.calibrate.estimate import C_MAX

from .verdict import print_held

__all__ = ["print_parameters", "print_not_trusted", "print_cautions", "write_result_file"]


def print_parameters(res) -> None:
    """The free parameters (value, sigma, unit, status), how many are held, and the residual test."""
    print(f"  {'parameter':<14} {'value':>14} {'sigma':>12}  unit       status")
    at_bound = []
    for nm in res.free:
        info = next(i for i in res.infos if i.name == nm)
        v, s = res.values[nm], res.sigma[nm]
        if info.unit == "rad/(N m)":
            bound = _at_bound(v, s)
            at_bound += [nm] if bound else []
            print(f"  {nm:<14} {v * 1e6:14.3f} {s * 1e6:12.3f}  urad/(N m) {res.status[nm]}{bound}")
        else:
            print(f"  {nm:<14} {v:14.5f} {s:12.5f}  {info.unit:<10} {res.status[nm]}")
    if at_bound:
        print(f"note: {', '.join(at_bound)} at a physical bound of a joint compliance (0 or {C_MAX:g} rad/(N m)): the "
              "data push it beyond, so its sigma describes one side only and the value is a limit, not a measurement",
              file=sys.stderr)
    print_held(res)
    if res.residual_check is not None:
        t = res.residual_check
        print(f"  residuals {t.wording}: {t.describe()}")


def _at_bound(value: float, sigma: float) -> str:
    """`` (at its bound)`` for a joint compliance [rad/(N m)] within a thousandth of its sigma of 0 or of
    :data:`~calibrate.estimate.C_MAX`, else ""."""
    tol = 1e-3 * max(sigma, 1e-12)
    return " (at its bound)" if value <= tol or value >= C_MAX - tol else ""


def print_cautions(res) -> None:
    """A trusted result's cautions (residuals slightly above the noise model, partial-turn periodic terms)."""
    for c in res.cautions:
        print(f"caution (trusted): {c}", file=sys.stderr)


def print_not_trusted(res) -> None:
    """The reasons not to trust a result, and its cautions (which hold for a later, trusted fit too)."""
    print("NOT TRUSTED - do not load these parameters into the robot:", file=sys.stderr)
    for w in res.warnings:
        print(f"  - {w}", file=sys.stderr)
    for c in res.cautions:
        print(f"caution: {c}", file=sys.stderr)


def write_result_file(args, result: dict) -> list:
    """The result file when ``--json`` is given, else the result in memory (for ``--report``)."""
    if args.json:
        path = write_result(args.json, result)
        print(f"wrote {path}")
        return [path]
    from ..report import Source
    return [Source(result["format"], result)]
