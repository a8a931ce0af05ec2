"""Physical plausibility of the joint-space parameters, and the constrained refit of an insignificant excursion.

A joint offset ``dtheta_i`` and a joint compliance ``c_i`` have a physical range (:data:`RANGES`: a few degrees of
zero error; a gearbox compliance in [0, 1e-4] rad/(N m)). An estimate outside it means one of two things:

- the data *show* it outside (beyond the range by more than :data:`SIGNIFICANT_Z` of its standard uncertainty):
  the robot file is not this robot, or the model misses something that drives the parameter; the result is not
  usable and :func:`calibrate.trust.trust_warnings` refuses it (the UR5 data calibrated as a UR10);
- the data *cannot tell* it from inside the range (beyond it by less than that): the estimate went there because
  the parameter is weakly determined and absorbs what the model leaves out (on the Kinova Gen3 lite, joint 2's
  backlash, a torque-sign-dependent step that a linear compliance fits with either sign:
  ``c_2 = 1.9e-4 +- 3.6e-4`` on one data set, ``-1.4e-4 +- 1.9e-4`` on the other). The physically constrained
  estimate is then the one to use: the parameter is held at the nearest end of its range (what a bounded least
  squares fit does with an active bound) and the rest refitted; the held-out (or cross-validated) accuracy of
  that refit decides whether it is usable. The hold and its reason are in the output and the result file's
  ``unidentifiable`` list.

Only the joint-space parameters are constrained: backlash, a gear's wind-up or a slack encoder act on the joint
angle, which is what ``dtheta_i`` and ``c_i`` describe. A length or twist beyond its manufacturing bound is left
to the refusal: there a wrong robot file shows (``a_2`` moved by 187 mm).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

from .trust import C_HIGH, C_LOW, C_TOLERANCE, ERROR_BOUNDS

if TYPE_CHECKING:
    from .identify import CalibrationResult

__all__ = ["RANGES", "TOLERANCE", "SIGNIFICANT_Z", "RangeHold", "excursions", "constrain_to_ranges"]

log = logging.getLogger(__name__)

#: physical range of each joint-space parameter kind, in contract units (dtheta: deg of zero error, the
#: manufacturing bound of :data:`calibrate.trust.ERROR_BOUNDS`; c: rad/(N m) of gearbox compliance)
RANGES = {"dtheta": (-ERROR_BOUNDS["dtheta"], ERROR_BOUNDS["dtheta"]), "c": (C_LOW, C_HIGH)}
#: how far below the range's low end an estimate may be without counting as outside (a rigid joint's compliance
#: estimated at -3e-7 is zero within its noise)
TOLERANCE = {"dtheta": 0.0, "c": C_TOLERANCE}
#: an estimate beyond its range by more than this many standard uncertainties is *shown* implausible (refused);
#: by less, the data cannot tell it from inside the range and it is held at the range's end
SIGNIFICANT_Z = 3.0
#: refits at most (each may push another weak parameter out of its range)
MAX_ROUNDS = 4


@dataclass(frozen=True)
class RangeHold:
    """One parameter held at the end of its physical range.

    name : parameter name (``c_2``); unit : its contract unit; estimate, sigma : the unconstrained fit's value and
    standard uncertainty [unit]; low, high : the physical range [unit]; held : the value it is held at [unit]
    """

    name: str
    unit: str
    estimate: float
    sigma: float
    low: float
    high: float

    def __post_init__(self):
        if not self.low < self.high:
            raise ValueError(f"{self.name}: range [{self.low}, {self.high}] is empty")
        if self.low < self.estimate < self.high:
            raise ValueError(f"{self.name} = {self.estimate} is inside its range: nothing to hold")

    @property
    def held(self) -> float:
        return self.high if self.estimate > self.high else self.low

    @property
    def z(self) -> float:
        """How far beyond the range, in standard uncertainties."""
        return abs(self.estimate - self.held) / self.sigma if self.sigma > 0 else float("inf")

    def reason(self) -> str:
        return (f"held at {self.held:.3g} {self.unit}, the end of its physical range [{self.low:g}, {self.high:g}]: "
                f"the fit put it at {self.estimate:.3g} +- {self.sigma:.2g} {self.unit}, outside by {self.z:.2f} of "
                f"its standard uncertainty, which these data cannot tell from inside the range (it absorbs what the "
                f"model leaves out, e.g. joint backlash); refitted with it held")


def excursions(res: "CalibrationResult") -> list[RangeHold]:
    """The free joint-space parameters of ``res`` outside their physical range (significant or not)."""
    out = []
    for info in res.infos:
        if info.kind not in RANGES or res.status[info.name] == "fixed":
            continue
        lo, hi = RANGES[info.kind]
        v = res.values[info.name]
        if not lo - TOLERANCE[info.kind] <= v <= hi:
            out.append(RangeHold(info.name, info.unit, v, float(res.sigma[info.name]), lo, hi))
    return out


def constrain_to_ranges(fit: Callable[[dict], "CalibrationResult"], pinned: dict | None = None, freed=()
                        ) -> tuple["CalibrationResult", dict]:
    """Fit with ``fit(pinned)``; while a joint-space parameter is outside its range by less than
    :data:`SIGNIFICANT_Z` standard uncertainties, hold it at the range's end and fit again. Returns the last
    result (its holds listed with the reason in ``unidentifiable`` and ``cautions``) and the pins it was fitted
    with (the user's and the holds, for the cross-validation of the same model). Parameters in ``freed`` (the
    user's ``--free``) are never held: the user asked for the unconstrained estimate, and the range check judges it."""
    pins = dict(pinned or {})
    holds: list[RangeHold] = []
    res = fit(pins)
    for _ in range(MAX_ROUNDS):
        new = [h for h in excursions(res) if h.z <= SIGNIFICANT_Z and h.name not in pins
               and h.name not in freed]
        if not new:
            break
        for h in new:
            log.info("%s %s", h.name, h.reason())
        holds += new
        pins.update({h.name: h.held for h in new})
        res = fit(pins)
    _record(res, holds)
    return res, pins


def _record(res: "CalibrationResult", holds: list[RangeHold]) -> None:
    names = {h.name for h in holds}
    res.unidentifiable = [u for u in res.unidentifiable if u.split(" (")[0] not in names] + [
        f"{h.name} ({h.reason()})" for h in holds]
    res.cautions = list(res.cautions) + [f"{h.name} {h.reason()}" for h in holds]
