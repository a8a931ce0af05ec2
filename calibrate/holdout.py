"""Held-out validation of instrument-point calibrations: split a point set, fit on one part, validate on the
rest (base and tool refitted on every validation set, the paper's Section 5.2), the nominal model as the
"before". Used by ``benchmarks/realdata_fanuc.py`` on public laser-tracker data and by the tests."""
from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .points_file import PointSet
from .params import ModelParams
from .points import identify_points
from .validate import ErrorStats, validate

__all__ = ["HoldoutRow", "subset", "interleaved", "fit_and_validate"]


@dataclass
class HoldoutRow:
    """One (fit, validation set) pair.

    protocol, test : names of the split and of the validation set; fit_points, test_points : counts;
    fit_rms_mm : residual rms of the fit [mm]; before / after : validation statistics of the nominal and the
    calibrated model [mm]; seconds : identification time [s]; held : parameters held at nominal because this
    fit could not identify them.
    """

    protocol: str
    test: str
    fit_points: int
    test_points: int
    fit_rms_mm: float
    before: ErrorStats
    after: ErrorStats
    seconds: float
    held: list


def subset(points: PointSet, mask: np.ndarray) -> PointSet:
    """The points selected by the boolean (or index) ``mask``."""
    return points.subset(mask)


def interleaved(points: PointSet) -> tuple[PointSet, PointSet]:
    """(even poses, odd poses) in file order: for sweeps of single joints, both halves span every sweep."""
    idx = np.arange(len(points.q_deg))
    return subset(points, idx % 2 == 0), subset(points, idx % 2 == 1)


def fit_and_validate(robot, protocol: str, fit: PointSet, tests: list[tuple[str, PointSet]],
                     pinned: dict | None = None, harmonics=()) -> list[HoldoutRow]:
    """Identify ``robot`` on ``fit`` (kinematics, base, tool, joint compliances; what the data cannot identify
    held at nominal; ``pinned`` name -> value held, e.g. every ``c_i = 0`` for a kinematic-only model;
    ``harmonics``: joints whose periodic errors are identified too) and validate on each named test set."""
    t0 = time.perf_counter()
    res = identify_points(robot, fit, None, pinned=pinned, fix_unidentifiable=True, harmonics=harmonics)
    seconds = time.perf_counter() - t0
    held = [u.split(" ")[0] for u in res.unidentifiable if "combined with" in u and "in this" in u]
    rows = []
    for name, test in tests:
        before = validate(robot, ModelParams.nominal(robot, test.tool_mm), test)[0]
        after = validate(robot, res.params, test)[0]
        rows.append(HoldoutRow(protocol, name, len(fit.q_deg), len(test.q_deg), res.rms_mm, before, after, seconds,
                               held))
    return rows
