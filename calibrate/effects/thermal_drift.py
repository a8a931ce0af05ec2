"""``thermal_drift``: the links grow during the campaign, so positions scale about the robot base with time or
temperature.

Two forms compete (the better fit is named; ``rod_share`` says which): the arm's links grow and the rod does not
(``rod_share`` 0: a carbon rod, the contract's physics; scaling every DH length by 1 + e moves the flange by e
times its position about the base, the rod rides along unscaled), or arm and rod grow alike (``rod_share`` 1: a
steel rod warming with the arm; the ball scales about the base).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.hypothesis import ParamSpec

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["ThermalDrift", "growth_lever_W"]


def growth_lever_W(frames, rod_share: float) -> np.ndarray:
    """What a unit growth moves each ball centre by, in {W} [mm], shape=(N, 3): the flange's position about the
    base (the links), plus ``rod_share`` times the rod's tool vector (the rod growing with them)."""
    flange_W = frames.o_i[:, -1] @ frames.R_W0.T + frames.t_W0
    return (flange_W - frames.t_W0) + rod_share * (frames.pW - flange_W)


class ThermalDrift(CampaignEffectModel):
    effect = "thermal_drift"
    order = 40
    params = (ParamSpec("growth_ppm_per_s", "ppm/s", "growth rate: positions scale about the base by rate x time_s"),
              ParamSpec("rod_share", "-", "how much the rod grows with the links: 0 a carbon rod (the links alone), "
                                          "1 a steel one (the ball scales about the base)", default=1.0,
                        magnitude=False))
    example = {"growth_ppm_per_s": 0.03}
    physics = "the arm warms up during the campaign and its links grow"
    signature = "the residuals grow with time_s (or temp_C) away from the robot base"
    locations = ("time", "temp")
    reported = ("`growth_ppm_per_s` [ppm/s] or `growth_ppm_per_K` [ppm/K] (needs the campaign's `time_s` / `temp_C`); "
                "`rod_share` 0 (the links grow, the rod does not) or 1 (the rod grows with them)")

    def reading_offset_W(self, frames, time_s: np.ndarray, p: dict):
        share = float(p.get("rod_share", 1.0))
        return p["growth_ppm_per_s"] * 1e-6 * np.round(time_s)[:, None] * growth_lever_W(frames, share)

    def truth(self, p: dict | None) -> dict:
        return {"thermal_ppm_per_s": 0.0 if p is None else float(p["growth_ppm_per_s"]),
                "thermal_rod_share": None if p is None else float(p.get("rod_share", 1.0))}

    def check(self, p: dict) -> None:
        if not 0.0 <= float(p.get("rod_share", 1.0)) <= 1.0:
            self.fail(f"effect {self.effect}: rod_share must lie in [0, 1] (0: the links alone grow, 1: the rod "
                      f"with them), got {p['rod_share']}", f"{self.effect}.rod_share")

    def hypotheses(self, ctx: CampaignContext) -> list:
        out = []
        for key, vals in (("time", ctx.time_s), ("temp", ctx.temp_C)):
            if vals is not None and np.isfinite(vals).all() and np.ptp(vals) > 0:
                v = (vals - vals.min())[:, None]
                for share in (0.0, 1.0):
                    H = (v * growth_lever_W(ctx.frames, share)).reshape(3 * ctx.n_points, 1) * 1e-6
                    grows = "the links grow" if share == 0 else "the links and the rod grow"
                    out.append(hypothesis(self.effect, key, [f"growth_ppm_per_{'s' if key == 'time' else 'K'}"], H,
                                          f"{grows} during the campaign: positions scale about the base with {key}",
                                          settings={"rod_share": share}))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        # refer the measured points to the campaign start: undo the growth about the robot base
        vals = ctx.time_s if location == "time" else ctx.temp_C
        rate = parameters["growth_ppm_per_s" if location == "time" else "growth_ppm_per_K"]
        g = rate * 1e-6 * (vals - vals.min())
        shift = g[:, None] * growth_lever_W(ctx.frames, parameters.get("rod_share", 1.0))
        fit.obs_edits.append(lambda obs: replace(obs, x_W_mm=obs.x_W_mm - shift))

    def remedy(self, location: str, parameters: dict) -> str:
        return ("the robot grew during the campaign: let it warm up to a steady temperature and record the "
                "campaign again (or shorter)")
