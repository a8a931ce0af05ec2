"""A clamping pose recorded off, looked for directly: each position's translation freed in turn.

On a robot with errors of its own (a backlash, a gear's periodic error), a clamping position recorded 0.3 mm off
spreads through the identification: the campaign diagnosis's robust scatter rises with the robot's errors and no
longer names ``fixture_pose``, and a validation file shows the calibration still far better than nominal (a review:
0.231 mm against ~0.8 nominal, 0.065 mm with the pose freed). Freeing each position's translation in turn
(``fixture_J_x/y/z``) and refitting says it plainly: the recorded pose is suspect where freeing it takes at least
half the residual's sum of squares away (the rule of a mix-up, :data:`~.mixups.MIXUP_GAIN`), and by what offset.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from .errors import CalibrationError
from .identify import identify
from .mixups import MIXUP_GAIN

__all__ = ["FixtureSuspect", "fixture_suspect"]

log = logging.getLogger(__name__)

#: an offset of a clamping pose below this [mm] is within what a probing of the fixture records
MIN_OFFSET_MM = 0.05


@dataclass(frozen=True)
class FixtureSuspect:
    """A clamping pose that looks recorded off.

    position : its label; offset_mm : shape=(3,) the fitted correction of its translation in {W} [mm];
    rms_mm : the residual with it freed [mm per reading]; rms_given_mm : as given
    """

    position: int
    offset_mm: tuple
    rms_mm: float
    rms_given_mm: float

    def reason(self) -> str:
        dx, dy, dz = self.offset_mm
        keys = " ".join(f"--free fixture_{self.position}_{k}" for k in "xyz")
        return (f"clamping position {self.position}'s recorded pose looks off by ({dx:+.3f}, {dy:+.3f}, {dz:+.3f}) mm: "
                f"with its translation freed the data fit to {self.rms_mm * 1e3:.1f} um rms per reading against "
                f"{self.rms_given_mm * 1e3:.1f} um as given; re-measure that position's pose in the fixture file, or "
                f"identify it with the robot ({keys})")


def fixture_suspect(robot, obs, rod, compensations, options, result) -> FixtureSuspect | None:
    """The clamping position whose translation, freed, fits the campaign best, when that takes at least half the
    sum of squares of ``result`` (the identification as given) away and moves the pose by at least
    :data:`MIN_OFFSET_MM`; None otherwise, or for a campaign of one position."""
    positions = sorted({int(g) for g in np.asarray(obs.group)}) if obs.group is not None else []
    if len(positions) < 2:
        return None
    best = None
    for j in positions:
        trial = _freed(robot, obs, rod, compensations, options, j)
        if trial is not None and (best is None or trial.rms_mm < best[1].rms_mm):
            best = (j, trial)
    if best is None:
        return None
    j, trial = best
    offset = tuple(float(trial.values[f"fixture_{j}_{k}"]) for k in "xyz")
    log.info("fixture check: position %d freed, rms %.4g mm against %.4g mm as given, offset %s", j, trial.rms_mm,
             result.rms_mm, offset)
    if trial.rms_mm > MIXUP_GAIN * result.rms_mm or float(np.linalg.norm(offset)) < MIN_OFFSET_MM:
        return None
    return FixtureSuspect(j, offset, float(trial.rms_mm), float(result.rms_mm))


def _freed(robot, obs, rod, compensations, options, j: int):
    """The identification with position ``j``'s translation freed, or None where it is refused."""
    freed = set(options.freed) | {f"fixture_{j}_{k}" for k in "xyz"}
    try:
        return identify(robot, obs, rod, compensations, replace(options, freed=frozenset(freed)))
    except CalibrationError as e:
        log.debug("fixture check: position %d freed refused (%s)", j, e)
        return None
