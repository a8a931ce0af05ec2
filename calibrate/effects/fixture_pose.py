"""``fixture_pose``: the recorded pose of one clamping position is off, so all its points share one offset."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import ParamSpec, location_parts

from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis

__all__ = ["FixturePose"]


class FixturePose(CampaignEffectModel):
    effect = "fixture_pose"
    order = 10
    params = (ParamSpec("position", "-", "the clamping position whose recorded pose is off", kind="int",
                        magnitude=False),
              ParamSpec("offset_mm", "mm", "offset added to the recorded position of the pose, in {W}", kind="vector"))
    example = {"position": 2, "offset_mm": [0.1, -0.08, 0.05]}
    physics = "the fixture file's pose of one clamping position is wrong (re-clamped, bumped, mis-measured)"
    signature = "the residuals of one position share one offset"
    locations = ("position:J",)
    reported = "`dx_mm`, `dy_mm`, `dz_mm` [mm, {W}]"

    required = ("position",)
    repeatable = True

    def check_layout(self, positions: int, points: int, n_joints: int, p: dict) -> None:
        if not 1 <= int(p["position"]) <= positions:
            self.fail(f"effect {self.effect}: position {p['position']} is not one of the campaign's positions "
                      f"1..{positions}", f"{self.effect}.position")

    def same_place(self, p: dict, q: dict) -> bool:
        return int(p["position"]) == int(q["position"])

    def recorded_fixture(self, j: int, pose: np.ndarray, p: dict) -> np.ndarray:
        if j != int(p["position"]):
            return pose
        out = np.array(pose, float, copy=True)
        out[:3] += np.asarray(p["offset_mm"], float)
        return out

    def truth(self, p: dict | None) -> dict:
        return {"fixture_error_mm": {} if p is None else {str(int(p["position"])): list(map(float, p["offset_mm"]))}}

    def hypotheses(self, ctx: CampaignContext) -> list:
        N, out = ctx.n_points, []
        for j in np.unique(ctx.position):
            if ctx.obs.fixture_T is not None and np.allclose(ctx.obs.fixture_T[int(j)], np.eye(4)):
                continue                                    # the world position: its pose defines {W}
            H = np.zeros((N, 3, 3))
            H[ctx.position == j, :, :] = np.eye(3)
            out.append(hypothesis(self.effect, f"position:{int(j)}", ["dx_mm", "dy_mm", "dz_mm"], H.reshape(3 * N, 3),
                                  "the recorded pose of this clamping position is off: all its points share one offset"))
        return out

    def refit(self, fit: Refit, location: str, parameters: dict, ctx: CampaignContext) -> None:
        j = location_parts(location)[1]
        fit.freed |= {f"fixture_{j}_{k}" for k in "xyz"}

    def remedy(self, location: str, parameters: dict) -> str:
        j = location_parts(location)[1]
        frees = " ".join(f"--free fixture_{j}_{k}" for k in "xyz")
        return (f"re-measure clamping position {j}'s pose, or identify its offset with the robot: re-run "
                f"`rodlab calibrate` with {frees}")
