"""``gauge_backlash`` (rodlab's addition to the vocabulary): lost motion in a dial gauge's plunger or rack — the
reading trails the displacement by half the play b in the direction the gauge last moved: moving out it reads
b/2 less, moving back b/2 more (it stays put until the play is taken up).

Friction splits the branches too, but by 2 F_f times the rod's compliance, so each gauge by its own entry
(an instrument trial's crossings of one load axis differed by gauge: x x +-32 g, x z +-14 g); lost motion
splits every gauge that moves by the same b, whatever it reads, and a gauge that does not move not at all.
The gauges are usually of one type: one b for all, or one gauge's alone."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["GaugeBacklash"]

_AXES = "xyz"
#: the largest play the hypothesis considers [mm] (a dial gauge's is a few um; more is a loose mounting)
_B_MAX = 0.1


class GaugeBacklash(RigEffectModel):
    effect = "gauge_backlash"
    order = 75
    params = (ParamSpec("backlash_mm", "mm", "the gauges' lost motion: a reading trails its displacement by half of "
                                             "it in the direction the gauge last moved"),
              ParamSpec("sensor", "-", "one gauge's alone (default: every gauge alike)", kind="str",
                        choices=tuple(_AXES)))
    example = {"backlash_mm": 0.004}
    physics = "lost motion (play) in the dial gauges' plungers or racks"
    signature = ("the branches split by the same b on every gauge that moves, whatever its compliance entry, and not "
                 "on a gauge that does not move")
    confirm = ("move each gauge's plunger by hand a little out and back against a fixed stop: the reading should lag "
               "by the fitted play; a gauge with a stronger spring or a digital one shows none")
    locations = ("sensor:x", "sensor:y", "sensor:z")

    def deflection(self, x, C, F, t, state, p):
        b = self.value(p, "backlash_mm")
        if not b:
            return x
        if state.gauge_contact is None:                     # zeroed on the series' first reading
            state.gauge_contact = np.array(x, float)
            return x
        which = [_AXES.index(p["sensor"])] if p.get("sensor") else range(3)
        r = state.gauge_contact
        for c in which:
            if x[c] - r[c] > b / 2:
                r[c] = x[c] - b / 2
            elif r[c] - x[c] > b / 2:
                r[c] = x[c] + b / 2
        out = np.array(x, float)
        out[list(which)] = r[list(which)]
        return out

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        col = _trailing(data, ctx.base)
        text = ("lost motion in the gauges' plungers: each reading trails its displacement by half the play in the "
                "direction the gauge last moved, the same on every gauge that moves")
        out = [Hypothesis(self.effect, None, ["backlash_mm"], col[:, None], [0.0], [_B_MAX], text)]
        for c in sorted(set(data.comp.tolist())):
            one = np.where(data.comp == c, col, 0.0)
            if np.any(one) and not np.array_equal(one, col):
                out.append(Hypothesis(self.effect, f"sensor:{_AXES[c]}", ["backlash_mm"], one[:, None], [0.0], [_B_MAX],
                                      f"lost motion in the {_AXES[c]} gauge's plunger: its readings trail its "
                                      "displacement by half the play in the direction it last moved"))
        return out


def _trailing(data, base: np.ndarray) -> np.ndarray:
    """Per sample, -1/2 times the direction its gauge last moved (the simulated displacement ``base``'s change from
    hold to hold within its series; 0 before the first move): the reading's change per unit play."""
    out = np.zeros(base.size)
    for g in np.unique(data.zero_groups):
        idx = np.nonzero(data.zero_groups == g)[0]
        idx = idx[np.argsort(data.t_abs[idx], kind="stable")]
        steps, first = np.unique(data.step[idx], return_index=True)
        order = np.argsort(first)
        level = {int(s): float(np.mean(base[idx][data.step[idx] == s])) for s in steps}
        direction, prev = 0.0, None
        moved = {}
        for s in steps[order]:
            s = int(s)
            if prev is not None:
                change = level[s] - level[prev]
                if abs(change) > 1e-12:
                    direction = float(np.sign(change))
            moved[s] = direction
            prev = s
        out[idx] = -0.5 * np.array([moved[int(s)] for s in data.step[idx]])
    return out
