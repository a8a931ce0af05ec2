"""``thermal_drift``: the links grow during the campaign, so positions scale about the robot base with time or
temperature."""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["ThermalDrift"]


class ThermalDrift(CampaignEffectModel):
    effect = "thermal_drift"
    order = 40
    params = (ParamSpec("growth_ppm_per_s", "ppm/s", "growth rate: positions scale about the base by rate x time_s"),)
    example = {"growth_ppm_per_s": 0.03}
    physics = "the arm warms up during the campaign and its links grow"
    signature = "the residuals grow with time_s (or temp_C) away from the robot base"
    locations = ("time", "temp")
    reported = "`growth_ppm_per_s` [ppm/s] or `growth_ppm_per_K` [ppm/K] (needs the campaign's `time_s` / `temp_C`)"

    def reading_offset_W(self, pW: np.ndarray, time_s: np.ndarray, base_W: np.ndarray, p: dict):
        return p["growth_ppm_per_s"] * 1e-6 * np.round(time_s)[:, None] * (pW - base_W)

    def truth(self, p: dict | None) -> dict:
        return {"thermal_ppm_per_s": 0.0 if p is None else float(p["growth_ppm_per_s"])}

    def hypotheses(self, ctx: CampaignContext) -> list:
        fr, N, out = ctx.frames, ctx.n_points, []
        for key, vals in (("time", ctx.time_s), ("temp", ctx.temp_C)):
            if vals is not None and np.isfinite(vals).all() and np.ptp(vals) > 0:
                v = (vals - vals.min())[:, None]
                H = (v * (fr.pW - fr.t_W0)).reshape(3 * N, 1) * 1e-6
                out.append(hypothesis(self.effect, key, [f"growth_ppm_per_{'s' if key == 'time' else 'K'}"], H,
                                      f"the links grow during the campaign: positions scale about the base with {key}"))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        # refer the measured points to the campaign start: undo the growth about the robot base
        vals = ctx.time_s if location == "time" else ctx.temp_C
        rate = parameters["growth_ppm_per_s" if location == "time" else "growth_ppm_per_K"]
        g = rate * 1e-6 * (vals - vals.min())
        centre = ctx.frames.t_W0
        fit.obs_edits.append(lambda obs: replace(obs, x_W_mm=obs.x_W_mm - g[:, None] * (obs.x_W_mm - centre)))

    def remedy(self, location: str, parameters: dict) -> str:
        return ("the robot grew during the campaign: let it warm up to a steady temperature and record the "
                "campaign again (or shorter)")
