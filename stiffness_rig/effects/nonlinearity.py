"""``nonlinearity``: a load-dependent stiffness, compliance C (1 + beta |F| / 10 N + beta2 F^2 / 100 N^2), on
every load axis or on one (a bearing, a contact or a tube that stiffens or softens under one direction of load)."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from .base import RigEffectModel

__all__ = ["Nonlinearity"]

_AXES = "xyz"


class Nonlinearity(RigEffectModel):
    effect = "nonlinearity"
    order = 40
    params = (ParamSpec("beta_per_10N", "-", "relative change of the compliance per 10 N of load"),
              ParamSpec("beta2_per_100N2", "-", "relative change of the compliance per (10 N)^2 of load: a curvature "
                        "that grows with the square of the load (optional)"),
              ParamSpec("axis", "-", "the load axis whose compliance changes, or all of them", "all", kind="str",
                        choices=("all",) + tuple(_AXES), magnitude=False))
    locations = ("null", "x", "y", "z")      # every load axis, or the one load axis whose stiffness changes
    example = {"beta_per_10N": 0.01}
    physics = "load-dependent stiffness"
    signature = "the slope changes with the load magnitude; residuals curved in the load"
    confirm = "add smaller and larger masses on this axis: the residual should stay curved in the load"

    def load_compliance(self, C, F, hold, p):
        if p.get("axis", "all") not in ("all", str(hold.axis.value).lstrip("-")):
            return C
        f = float(np.linalg.norm(F))
        return C * (1.0 + self.value(p, "beta_per_10N") * f / 10.0 + self.value(p, "beta2_per_100N2") * f * f / 100.0)

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        """The simulator's forms, each one term (the selection takes at most one): linear in |F| and quadratic in
        F on every axis, and linear on one load axis (location ``x``, ``y``, ``z``, where the recording loads
        more than one). Fitted by the linear form alone, a quadratic one came with a compensating
        ``compliance_scale`` and ``tare``, a one-axis one with a joint spring. A gauge's own non-linearity looks
        like the one-axis form on that axis's main gauge; the diagnosis models it beside these
        (:mod:`rodlab.app.diagnose.rig_outside`) so that it is not forced onto this effect."""
        return [Hypothesis(self.effect, None, ["beta_per_10N"], (ctx.base * np.abs(data.F) / 10.0)[:, None],
                           [-1.0], [1.0],
                           "a load-dependent stiffness bends the load-deflection line: the slope changes with the "
                           "load"),
                Hypothesis(self.effect, None, ["beta2_per_100N2"], (ctx.base * data.F ** 2 / 100.0)[:, None],
                           [-1.0], [1.0],
                           "a load-dependent stiffness bends the load-deflection line: the slope changes with the "
                           "square of the load")] + self._one_axis(data, ctx)

    def _one_axis(self, data, ctx) -> list[Hypothesis]:
        axes = sorted(set(data.axis.tolist()))
        return [Hypothesis(self.effect, _AXES[a], ["beta_per_10N"],
                           (ctx.base * np.abs(data.F) / 10.0 * (data.axis == a))[:, None], [-1.0], [1.0],
                           f"the stiffness changes with the load along {_AXES[a]} only (a bearing, a contact or a "
                           f"tube that stiffens or softens under that load)") for a in axes] if len(axes) > 1 else []
