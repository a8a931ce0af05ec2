"""What ``rodlab calibrate`` (campaign, points, sockets) prints and writes of an identification."""
from __future__ import annotations

import csv
import io
import sys
from pathlib import Path

import numpy as np

from rodlab.calibrate import write_result
from rodlab.calibrate.estimate import C_MAX
from rodlab.core.fileio import atomic_write_text

from .verdict import print_held

__all__ = ["print_parameters", "print_not_trusted", "print_cautions", "write_result_file", "write_residuals"]


def print_parameters(res) -> None:
    """The free parameters (value, sigma, unit, status), how many are held, and the residual test."""
    print(f"  {'parameter':<14} {'value':>14} {'sigma':>12}  unit       status")
    at_bound = []
    for nm in res.free:
        info = next(i for i in res.infos if i.name == nm)
        v, s = res.values[nm], res.sigma[nm]
        if info.unit == "rad/(N m)":
            bound = _at_bound(v, s)
            at_bound += [nm] if bound and res.status[nm] == "identified" else []
            print(f"  {nm:<14} {v * 1e6:14.3f} {s * 1e6:12.3f}  urad/(N m) {res.status[nm]}{bound}")
        else:
            print(f"  {nm:<14} {v:14.5f} {s:12.5f}  {info.unit:<10} {res.status[nm]}")
    if at_bound:
        print(f"note: {', '.join(at_bound)} at a physical bound of a joint compliance (0 or {C_MAX:g} rad/(N m)): the "
              "data push it beyond, so its sigma describes one side only and the value is a limit, not a measurement",
              file=sys.stderr)
    _note_unidentified_compliance(res)
    _warn_negative(res)
    print_held(res)
    if res.residual_check is not None:
        t = res.residual_check
        print(f"  residuals {t.wording}: {t.describe()}")


def _note_unidentified_compliance(res) -> None:
    """One line where the data cannot identify the free joint compliances (each ``regularised``: its sigma from
    the data alone beyond a joint's physical size): the fit keeps them near their start values, and says how
    to measure them (a trial: five compliances of sigma 40-117,000 urad/(N m) read as results)."""
    free_c = [nm for nm in res.free if next(i for i in res.infos if i.name == nm).unit == "rad/(N m)"]
    weak = [nm for nm in free_c if res.status[nm] == "regularised"]
    if not weak:
        return
    which = ("the joint compliances are" if len(weak) == len(free_c) else
             f"{', '.join(weak)} {'is' if len(weak) == 1 else 'are'}")
    print(f"note: {which} not identifiable from these data (sigma beyond a joint's physical size): the fit keeps "
          f"them near their start values (a prior), so read them as those, not as measurements; to identify them, "
          f"measure the same poses under different loads (the rod's own weight at other arm postures, a payload)",
          file=sys.stderr)


#: a joint compliance held at 0 whose unbounded estimate lies this many sigma below 0 is a sag of the wrong sign
NEGATIVE_SIGMAS = 3.0


def _warn_negative(res) -> None:
    """Each joint compliance held at 0 that the data, unbounded, put clearly below it: the points sag the wrong
    way under gravity (a trial: a measured-minus-target column of the other sign moved the compliance from one joint
    to another, both fits trusted)."""
    for nm, v in res.unconstrained.items():
        s = res.sigma.get(nm, 0.0)
        if s > 0 and v < -NEGATIVE_SIGMAS * s:
            print(f"warning: {nm} is held at 0; unbounded, the data put it at {v * 1e6:.1f} urad/(N m) ({v / s:.0f} "
                  f"sigma): no joint is stiffer than rigid, so the points bend against the gravity sag the model "
                  f"predicts there, and the other joint compliances of this fit carry what it cannot. Before reading "
                  f"them as physics, check the sign convention of the measured points (measured - target or target "
                  f"- measured?), the axis directions and the link masses of the robot file", file=sys.stderr)


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


def write_residuals(path, res, q_deg, labels=None) -> Path:
    """Each point's residual of the identification ``res`` as a CSV (``--residuals``): ``row`` (the point's place
    among the file's data rows, from 1), ``label`` (a campaign's ``position.point``, a points file's name),
    ``q1..qn`` [deg] as read, ``dx_mm, dy_mm, dz_mm`` measured minus model in {W} (the instrument's frame for
    points, the world position's {D} for a campaign) and ``norm_mm``; atomically (a trial: the per-point residuals
    had been in no file)."""
    r = np.asarray(res.residuals_mm, float).reshape(-1, 3)
    q = np.asarray(q_deg, float)
    buf = io.StringIO()
    out = csv.writer(buf, lineterminator="\n")
    out.writerow(["row"] + (["label"] if labels is not None else []) + [f"q{i + 1}" for i in range(q.shape[1])]
                 + ["dx_mm", "dy_mm", "dz_mm", "norm_mm"])
    for k, (qk, rk) in enumerate(zip(q, r)):
        out.writerow([k + 1] + ([labels[k]] if labels is not None else []) + [f"{v:.6f}" for v in qk]
                     + [f"{v:.6f}" for v in rk] + [f"{np.linalg.norm(rk):.6f}"])
    written = atomic_write_text(path, buf.getvalue())
    print(f"wrote {written}")
    return written
