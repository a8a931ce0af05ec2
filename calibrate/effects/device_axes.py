"""``device_axes``: the device's sensor axes are not those its readings were converted with (sensors off
orthogonal read as orthogonal, or a wrong device file), so every point is off by a linear map of its offset from
the datum point, the same map in {D} at every position."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["DeviceAxes"]

#: the map's entries the {D} convention leaves free: sensor 2 towards x, sensor 3 towards x, sensor 3 towards y
#: (row, column of E in x_read = (I + E) x_true)
ENTRIES = ((1, 0), (2, 0), (2, 1))
NAMES = ["sensor2_x_deg", "sensor3_x_deg", "sensor3_y_deg"]


def _map(angles_deg) -> np.ndarray:
    """E (3, 3) of the small misalignment angles [deg]: each axis tilted by its angle towards the named one."""
    E = np.zeros((3, 3))
    for (r, c), a in zip(ENTRIES, np.asarray(angles_deg, float)):
        E[r, c] = np.sin(np.radians(a))
    return E


class DeviceAxes(CampaignEffectModel):
    effect = "device_axes"
    order = 60
    params = (ParamSpec("misalign_deg", "deg", "sensor 2 tilted towards x, sensor 3 towards x, sensor 3 towards y, "
                        "against the axes the readings are converted with", kind="vector"),)
    example = {"misalign_deg": [2.0, -1.5, 1.0]}
    physics = ("the device's sensor axes are not those its readings were converted with (sensors off orthogonal "
               "read as orthogonal, a wrong device file)")
    signature = "residuals linear in each point's offset from the datum point, one map in {D} at every position"
    locations = ("null",)
    reported = "`sensor2_x_deg`, `sensor3_x_deg`, `sensor3_y_deg` [deg] (each axis' tilt the conversion left out)"

    def check(self, p: dict) -> None:
        if not np.all(np.abs(np.asarray(p["misalign_deg"], float)) < 10.0):
            self.fail(f"effect {self.effect}: misalign_deg must be small angles (|a| < 10 deg), got "
                      f"{p['misalign_deg']}", f"{self.effect}.misalign_deg")

    def corrupt(self, xD: np.ndarray, labels: list, rng: np.random.Generator, p: dict) -> tuple[np.ndarray, dict]:
        """Every reading as the misaligned sensors give it, converted as if they were the assumed ones."""
        xD = np.asarray(xD, float)
        return xD + xD @ _map(p["misalign_deg"]).T, {}

    def hypotheses(self, ctx: CampaignContext) -> list:
        obs = ctx.obs
        if obs.x_D_mm is None or obs.fixture_T is None or obs.group is None:
            return []
        N = ctx.n_points
        H = np.zeros((N, 3, 3))
        for k, (r, c) in enumerate(ENTRIES):
            e = np.zeros((N, 3))
            e[:, r] = obs.x_D_mm[:, c]
            for j, T in obs.fixture_T.items():
                m = obs.group == j
                H[m, :, k] = e[m] @ T[:3, :3].T
        return [hypothesis(self.effect, None, NAMES, H.reshape(3 * N, 3),
                           "the device's sensor axes are not those its readings were converted with: every point is "
                           "off by one linear map of its offset from the datum point",
                           report_scale=np.full(3, 180.0 / np.pi))]

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        E = _map([parameters[n] for n in NAMES])

        def corrected(obs):
            dx = obs.x_D_mm @ np.linalg.inv(np.eye(3) + E).T - obs.x_D_mm       # x_true - x_read in {D}
            xW = obs.x_W_mm.copy()
            for j, T in obs.fixture_T.items():
                m = obs.group == j
                xW[m] += dx[m] @ T[:3, :3].T
            return replace(obs, x_W_mm=xW, x_D_mm=obs.x_D_mm + dx)
        fit.obs_edits.append(corrected)

    def remedy(self, location: str, parameters: dict) -> str:
        tilts = ", ".join(f"{n[:-4]} {parameters[n]:+.2f} deg" for n in NAMES)
        return (f"the sensors' axes are off those used to convert the readings ({tilts}): calibrate the device (or "
                f"take its calibrated axes) and give them in the device file (--device)")
