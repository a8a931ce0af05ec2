"""``outliers``: isolated gross alignment errors at single points (a misread, a bumped device)."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["Outliers"]


class Outliers(CampaignEffectModel):
    effect = "outliers"
    order = 50
    params = (ParamSpec("count", "-", "how many readings get a gross error", default=2, kind="int", magnitude=False),
              ParamSpec("min_mm", "mm", "smallest error per coordinate (sign random)"),
              ParamSpec("max_mm", "mm", "largest error per coordinate"))
    example = {"min_mm": 0.15, "max_mm": 0.4}
    physics = "single readings with a gross error (misread, bumped device, ball not seated)"
    signature = "a few isolated points far off, their neighbours fine"
    locations = ("points:J.I,J.I",)
    reported = "`dx_mm`, `dy_mm`, `dz_mm` [mm, {W}] of the first point listed"
    per_point = True

    def check(self, p: dict) -> None:
        if not 0 <= p["min_mm"] <= p["max_mm"]:
            self.fail(f"effect {self.effect}: need 0 <= min_mm <= max_mm, got {p['min_mm']}, {p['max_mm']}",
                      f"{self.effect}.min_mm")

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        if int(p["count"]) > points:
            self.fail(f"effect {self.effect}: count {p['count']} exceeds the campaign's {points} points",
                      f"{self.effect}.count")

    def corrupt(self, xD: np.ndarray, labels: list, rng: np.random.Generator, p: dict) -> tuple[np.ndarray, dict]:
        n = int(p["count"])
        idx = np.sort(rng.choice(len(labels), size=n, replace=False))
        out = np.array(xD, float, copy=True)
        out[idx] += rng.choice([-1.0, 1.0], (n, 3)) * rng.uniform(p["min_mm"], p["max_mm"], (n, 3))
        return out, {"outlier_points": [labels[i] for i in idx]}

    def point_hypothesis(self, i: int, ctx: CampaignContext):
        N = ctx.n_points
        H = np.zeros((N, 3, 3))
        H[i] = np.eye(3)
        return hypothesis(self.effect, f"points:{ctx.labels[i]}", ["dx_mm", "dy_mm", "dz_mm"], H.reshape(3 * N, 3),
                          "an isolated gross alignment error at this point")

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        for lab in location_parts(location)[1].split(","):
            fit.keep[ctx.labels.index(lab)] = False

    def remedy(self, location: str, parameters: dict) -> str:
        return (f"re-measure points {location_parts(location)[1]} (a gross alignment error), or calibrate with "
                "--robust to down-weight them")
