"""``device_zero``: the readings were converted with another zero than the device aligned the ball with (a device
file whose ``zero_mm`` is not the recording device's, a tip replaced, a sensor re-zeroed), so every ball centre is off
by one offset in {D}, the same at every clamping position and turned by each position's orientation in {W} (rodlab's
addition to the contract's vocabulary). A device trial: a sensor read 0.8 mm off its file's zero had been diagnosed
``unexplained`` at one position, where ``rodlab calibrate`` had named the common offset.

The offset shows in the readings themselves: the robot aligned the ball with the datum point, so the converted
centres share it (:func:`readings_offset`: their mean, clearly off zero). The hypothesis is offered only then, with one
parameter, the share of that common offset the residuals carry (1: all of it a zero error): fitted freely as three
offsets it is nearly lost among the kinematic parameters (a trial: -32 +- 100 mm for a 0.8 mm zero). The offset it
reports is the readings' mean, so it carries whatever mean the alignment itself left (within 0.05 mm on rod 1#;
0.2 mm on a rod soft enough for the springs to push its ball off the aligned point).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["DeviceZero", "readings_offset"]

NAMES = ["dx_mm", "dy_mm", "dz_mm"]
#: the largest zero error a device keeps its ball within its sensors' strokes with [mm]
MAX_OFFSET_MM = 10.0
#: the readings' mean must lie this many standard errors off the datum point, and this far [mm], to be a zero error
OFFSET_Z, OFFSET_MIN_MM = 6.0, 0.05


def readings_offset(x_D_mm: np.ndarray) -> np.ndarray | None:
    """The mean [mm] of the converted ball centres in {D} where it lies clearly off the datum point (beyond
    :data:`OFFSET_Z` standard errors of the points' alignment scatter and :data:`OFFSET_MIN_MM`), else None: the
    robot aligned each ball with the datum, so the mean of many is near zero unless the zero is off."""
    x = np.asarray(x_D_mm, float)
    if x.ndim != 2 or len(x) < 6:
        return None
    mean = x.mean(axis=0)
    se = np.linalg.norm(x.std(axis=0, ddof=1)) / np.sqrt(len(x))
    size = float(np.linalg.norm(mean))
    return mean if size > OFFSET_MIN_MM and size > OFFSET_Z * se else None


class DeviceZero(CampaignEffectModel):
    effect = "device_zero"
    order = 65
    params = (ParamSpec("offset_mm", "mm", "offset of every ball centre in {D}: the readings' zero against the "
                        "device file's", kind="vector"),)
    example = {"offset_mm": [0.3, -0.1, 0.2]}
    physics = ("the device reads from another zero than its file states (zero_mm off, a tip replaced, a sensor "
               "re-zeroed)")
    signature = "the residuals of each position share one offset, the same in {D} at every position"
    locations = ("null",)
    reported = ("`share` [-] of the readings' common offset that is a zero error, beside that offset `dx_mm`, "
                "`dy_mm`, `dz_mm` [mm, {D}]")

    def check(self, p: dict) -> None:
        if not np.all(np.abs(np.asarray(p["offset_mm"], float)) < MAX_OFFSET_MM):
            self.fail(f"effect {self.effect}: offset_mm must be within +-{MAX_OFFSET_MM:g} mm (a sensor's stroke), "
                      f"got {p['offset_mm']}", f"{self.effect}.offset_mm")

    def corrupt(self, xD: np.ndarray, labels: list, rng: np.random.Generator, p: dict) -> tuple[np.ndarray, dict]:
        """Every reading converted with the file's zero where the device reads from another."""
        return np.asarray(xD, float) + np.asarray(p["offset_mm"], float), {}

    def hypotheses(self, ctx: CampaignContext) -> list:
        obs = ctx.obs
        if obs.fixture_T is None or obs.group is None or obs.x_D_mm is None:
            return []
        offset = readings_offset(obs.x_D_mm)
        if offset is None:
            return []
        N = ctx.n_points
        H = np.zeros((N, 3))
        for j, T in obs.fixture_T.items():
            H[obs.group == j] = T[:3, :3] @ offset
        return [hypothesis(self.effect, None, ["share"], H.reshape(3 * N, 1),
                           "the readings were converted with another zero than the device aligned the ball with: every "
                           "ball centre is off by one offset in {D}, at every clamping position",
                           settings={n: round(float(v), 4) for n, v in zip(NAMES, offset)})]

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        d = float(parameters["share"]) * np.array([parameters[n] for n in NAMES], float)

        def corrected(obs):
            xW = obs.x_W_mm.copy()
            for j, T in obs.fixture_T.items():
                xW[obs.group == j] -= T[:3, :3] @ d
            return replace(obs, x_W_mm=xW, x_D_mm=None if obs.x_D_mm is None else obs.x_D_mm - d)
        fit.obs_edits.append(corrected)

    def remedy(self, location: str, parameters: dict) -> str:
        d = ", ".join(f"{float(parameters.get('share', 1.0)) * parameters[n]:+.3f}" for n in NAMES)
        return (f"the device reads off its file's zero by ({d}) mm in {{D}}: the zero it read from is the device "
                f"file's zero_mm + reading_sign x axis_D . d for each sensor (for sensors along x, y, z that read "
                f"along them: each zero_mm plus that component; a sensor with reading_sign -1: minus it); correct "
                f"zero_mm and give the file with --device, or, for a campaign of ball centres, "
                f"subtract ({d}) from its x/y/z_mm; better, re-zero the sensors at the datum point and measure again")
