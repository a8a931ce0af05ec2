"""The zero-load crossings of a rig fit's load-deflection lines: the load where a line passes the unloaded
reference reading (friction splits the branches' crossings by 2 F_f / g0; a dead load missing from ``mass_kg``
shifts both), and their standard errors by the delta method."""
from __future__ import annotations

import numpy as np

from rodlab.core.units import G0

__all__ = ["reference_level", "zero_load_se"]


def reference_level(holds, ref: np.ndarray, c: int, noise: float) -> tuple[float, float]:
    """The reading [mm] of component ``c`` on the axis's unloaded reference hold (``ref`` selects it) and its
    variance [mm^2]; (0, 0) without one. The zero-load crossings are taken from this level, not from the gauge's
    zero: a gauge zeroed on a single reading sits one reading's noise off, which read as a +15 g dead load at 18
    standard errors on an independent null recording."""
    idx = np.flatnonzero(ref)
    if idx.size == 0 or not np.isfinite(holds.mean_mm[idx[0], c]):
        return 0.0, 0.0
    i = idx[0]
    var = noise ** 2 / max(float(holds.n[i]), 1.0) if np.isfinite(noise) else float(holds.std_mm[i, c]) ** 2
    return float(holds.mean_mm[i, c]), float(var) if np.isfinite(var) else 0.0


def zero_load_se(coef: np.ndarray, cov: np.ndarray, i: int, sign: float, y0: float = 0.0,
                 var0: float = 0.0) -> float:
    """The standard error [kg] of the zero-load crossing ``-(a_i - y0) / (b g0 sign)`` of intercept ``i`` and the
    slope (the last coefficient) from the reference level ``y0`` (variance ``var0``, independent of the line's
    holds), by the delta method (a blind trial: +67 / +77 g crossings without one had read like the paper's
    friction, where they were noise)."""
    a, b = float(coef[i]) - y0, float(coef[-1])
    grad = np.zeros(coef.size)
    grad[i], grad[-1] = -1.0 / (b * G0 * sign), a / (b * b * G0 * sign)
    return float(np.sqrt(max(grad @ cov @ grad + var0 / (b * G0) ** 2, 0.0)))
