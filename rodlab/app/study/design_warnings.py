"""What a study says about a design's predicted accuracy beyond its numbers (:class:`~rodlab.core.enums.StudyWarning`).

Three situations a designer must not read past in the table:

- the method the recommendation is for (Meas, else FEA, ...) leaves the robot *less* accurate than its nominal
  (uncalibrated) model: calibrating with this rod does harm (a soft rod whose non-repeatable deflection swamps the
  campaign); the recommendation leaves such a design out by the same rule;
- the rod's slip (:mod:`rodlab.calibrate.rod_slip`, ``--rod-slip``) is most of the best method's error: the methods
  then differ by how the identification absorbs scatter, not by what they compensate, so their ranking says little
  and a stiffer rod is what helps;
- the rod is far softer than the rods the default slip was fitted on (the paper's Table 2,
  :data:`~rodlab.core.units.PAPER_C_ROD_UM_RANGE`): the slip's size is an extrapolation; the study should be read
  beside one with ``--rod-slip 0``.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from rodlab.core.enums import StudyWarning
from rodlab.core.units import PAPER_C_ROD_UM_RANGE

from .table import harms, headline_method

__all__ = ["DesignWarning", "study_warnings", "warning_lines", "SLIP_DOMINANT_SHARE", "METHODS_APART",
           "SLIP_EXTRAPOLATION_FACTOR", "GROUPED_AFTER"]

#: the slip's share of the best method's mean-square error above which it is said to dominate (the paper's steel
#: rods 4# and 6# on the TX90: 0.97-0.99, where Table 3's methods differ by 5 %; carbon 1#: 0.6)
SLIP_DOMINANT_SHARE = 0.9
#: ... and the methods' means within this fraction of the best: further apart, what they compensate still shows (a
#: trial's carbon rod on a UR10: None 1.209 mm, Meas 0.792 mm, the rod's deflection 58 % of None's error)
METHODS_APART = 0.25
#: c_rod beyond this factor times the softest rod the slip was fitted on is called an extrapolation
SLIP_EXTRAPOLATION_FACTOR = 2.0


#: a kind of warning on more designs than this is said once for all of them (a designer trial: 19 designs' four-line
#: slip warnings had pushed the study's tables a screen down)
GROUPED_AFTER = 3


@dataclass(frozen=True)
class DesignWarning:
    """One warning on one design: ``kind``, the ``design``'s label, the ``text`` a designer reads and the
    ``value`` it turns on (the slip's share [-], c_rod [um], the method's mean error [mm])."""

    kind: StudyWarning
    design: str
    text: str
    value: float = math.nan

    def to_dict(self) -> dict:
        return {"kind": str(self.kind), "design": self.design, "text": self.text, "value": self.value}


def _best(rows):
    return rows.loc[rows["mean_mm"].idxmin()]


def _worse_than_nominal(design: str, rows, method: str) -> DesignWarning | None:
    """With the recommendation's ``method`` (:func:`~.table.headline_method`) the design leaves the robot less
    accurate than uncalibrated (:func:`~.table.harms`, as the recommendation judges it)."""
    head = rows[rows["method"] == method]
    if head.empty or not bool(harms(head).iloc[0]):
        return None
    nominal = float(head["nominal_mean_mm"].iloc[0])
    others = rows[~harms(rows)]
    tail = (f"; {', '.join(f'{r.method} {r.mean_mm:.3f} mm' for r in others.itertuples())} would not"
            if len(others) else ": calibrating with this rod would do harm with every method")
    return DesignWarning(StudyWarning.WORSE_THAN_NOMINAL, design, (
        f"{design}: with {method} compensation it leaves the robot less accurate than its nominal model "
        f"({head['mean_mm'].iloc[0]:.3f} mm against {nominal:.3f} mm uncalibrated){tail}"),
        float(head["mean_mm"].iloc[0]))


def _slip_dominates(design: str, rows, rod_slip: float) -> DesignWarning | None:
    best = _best(rows)
    share = float(best.get("share_slip", math.nan))
    spread = float(rows["mean_mm"].max() - rows["mean_mm"].min())
    if not rod_slip or not math.isfinite(share) or share <= SLIP_DOMINANT_SHARE:
        return None
    if spread > METHODS_APART * float(rows["mean_mm"].min()):     # the compensation still shows: ranking real
        return None
    return DesignWarning(StudyWarning.SLIP_DOMINATES, design, (
        f"{design}: the rod's slip (--rod-slip {rod_slip:g}: its non-repeatable deflection, {rod_slip:g} x its "
        f"deflection under its own weight, which no compensation removes) is {100 * share:.0f} % of the best "
        f"method's mean-square error; the methods differ by {spread:.3f} mm, by how the identification absorbs "
        "that scatter rather than by what they compensate: their ranking says little here, a stiffer rod is what "
        "helps"), share)


def _slip_extrapolated(design: str, rows, rod_slip: float) -> DesignWarning | None:
    c_rod = float(rows["c_rod_um"].iloc[0])
    limit = SLIP_EXTRAPOLATION_FACTOR * PAPER_C_ROD_UM_RANGE[1]
    if not rod_slip or not math.isfinite(c_rod) or c_rod <= limit:
        return None
    lo, hi = PAPER_C_ROD_UM_RANGE
    return DesignWarning(StudyWarning.SLIP_EXTRAPOLATED, design, (
        f"{design}: c_rod {c_rod:.0f} um is {c_rod / hi:.1f} x the softest rod the slip {rod_slip:g} was fitted on "
        f"(the paper's rods, c_rod {lo:g}-{hi:g} um): its size is an extrapolation; read this design beside a "
        "study with --rod-slip 0 (the elastic rod: what the compensation methods can do)"), c_rod)


def study_warnings(df, rod_slip: float) -> list[DesignWarning]:
    """The warnings on every usable design of the study table ``df`` (:func:`~.table.study_table`), in the
    table's design order; ``rod_slip``: the priors' slip the predictions were made with."""
    ok = df[(df["status"] == "ok") & df["method"].notna()]
    out = []
    if ok.empty:
        return out
    method = headline_method(ok)
    for design, rows in ok.groupby("design", sort=False):
        for check in (lambda d, r: _worse_than_nominal(d, r, method), lambda d, r: _slip_dominates(d, r, rod_slip),
                      lambda d, r: _slip_extrapolated(d, r, rod_slip)):
            w = check(str(design), rows)
            if w is not None:
                out.append(w)
    return out


#: what a kind of warning says for many designs at once: the sentence after their names, given the range of values
_GROUPED = {
    StudyWarning.WORSE_THAN_NOMINAL: lambda lo, hi: (
        f"with the recommendation's method they leave the robot less accurate than its nominal model ({lo:.3f}-"
        f"{hi:.3f} mm); the recommendation leaves them out while another design helps"),
    StudyWarning.SLIP_DOMINATES: lambda lo, hi: (
        f"the rod's slip (--rod-slip: its non-repeatable deflection, which no compensation removes) is "
        f"{100 * lo:.0f}-{100 * hi:.0f} % of the best method's mean-square error: the methods' ranking says little "
        "there, a stiffer rod is what helps"),
    StudyWarning.SLIP_EXTRAPOLATED: lambda lo, hi: (
        f"c_rod {lo:.0f}-{hi:.0f} um, beyond the rods the slip was fitted on: its size is an extrapolation; read them "
        "beside a study with --rod-slip 0"),
}


def warning_lines(warnings) -> list[str]:
    """The warnings as a designer reads them: each on its own where a kind concerns at most :data:`GROUPED_AFTER`
    designs, else one line for the kind naming how many and which (the first few), the range of its values, and
    where each design's own sentence is (``study.json``)."""
    out = []
    kinds = list(dict.fromkeys(w.kind for w in warnings))
    for kind in kinds:
        group = [w for w in warnings if w.kind == kind]
        if len(group) <= GROUPED_AFTER:
            out += [w.text for w in group]
            continue
        names = ", ".join(w.design for w in group[:3]) + (", ..." if len(group) > 3 else "")
        values = [w.value for w in group if math.isfinite(w.value)]
        lo, hi = (min(values), max(values)) if values else (math.nan, math.nan)
        out.append(f"{len(group)} designs ({names}): {_GROUPED[kind](lo, hi)} (each design's own warning: "
                   "study.json `warnings`)")
    return out
