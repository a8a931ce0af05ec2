"""The parameter vector of the calibration (paper Eq. 3) and the structural identifiability rules.

Catalogue per joint i: ``dtheta_i`` [deg], ``d_i``, ``a_i`` [mm], ``alpha_i``, ``beta_i`` [deg], ``c_i``
[rad/(N m)]; on request, per chosen joint, the periodic joint errors ``h1s_i, h1c_i, h2s_i, h2c_i`` [deg];
``base_x, base_y, base_z`` [mm], ``base_a, base_b, base_c`` [deg] (pose of {0} in {W}); ``tool_x, tool_y,
tool_z`` [mm] (ball centre in {n}). Internally the optimiser works in mm, mrad and
urad/(N m) so that every column has a similar scale.

Structural rules (always true for a serial robot measured by ball positions):
- ``dtheta_1`` and ``d_1`` move the arm as the base does: absorbed by the base pose;
- the last row's ``d_n``, ``a_n`` are the tool's z and x; ``alpha_n``, ``beta_n`` tilt the tool point as
  ``dtheta_n`` and ``tool_y`` do; with a rod (tool_x != 0) ``tool_y`` is held 0 and ``dtheta_n`` carries the
  rod's mounting twist (contract);
- on a row whose axis is parallel to the next (alpha = 0) ``beta`` is identified instead of ``d`` (Hayati);
  on other rows ``beta`` is held 0;
- joint 1 carries no gravity torque: ``c_1`` is held 0.
What the campaign itself cannot separate is found numerically (:mod:`calibrate.identify`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .kinematics import HARMONICS, ModelParams

__all__ = ["ParamInfo", "catalogue", "structural_fixed", "apply", "INTERNAL_SCALE", "PRIOR_SCALE"]

#: internal unit per contract unit
INTERNAL_SCALE = {"mm": 1.0, "deg": 1e3 * np.pi / 180.0, "rad/(N m)": 1e6}
#: physical size used to judge (and regularise) weakly identified parameters, in contract units
PRIOR_SCALE = {"mm": 2.0, "deg": 0.2, "rad/(N m)": 1e-5}


@dataclass(frozen=True)
class ParamInfo:
    name: str
    kind: str          # dtheta | d | a | alpha | beta | c | h1s | h1c | h2s | h2c | base_t | base_r | tool | fixture
    index: int         # joint index (0-based) or component
    unit: str


def catalogue(n: int, positions=(), harmonics=()) -> list[ParamInfo]:
    """All candidate parameters, in the preference order of the rank analysis.

    ``positions``: clamping positions whose translation offsets ``fixture_J_x/y/z`` (a correction to the
    recorded pose of {D_J}) exist as parameters; they are held fixed unless freed.
    ``harmonics``: joints (1-based) whose periodic errors ``h1s_j .. h2c_j`` are parameters (after every
    geometric and compliance parameter, so that the rank analysis gives way to those first).
    """
    out = [ParamInfo(f"base_{k}", "base_t", i, "mm") for i, k in enumerate("xyz")]
    out += [ParamInfo(f"base_{k}", "base_r", i, "deg") for i, k in enumerate("abc")]
    out += [ParamInfo(f"tool_{k}", "tool", i, "mm") for i, k in enumerate("xzy")]
    for i in range(n):
        j = i + 1
        out += [ParamInfo(f"dtheta_{j}", "dtheta", i, "deg"), ParamInfo(f"a_{j}", "a", i, "mm"),
                ParamInfo(f"alpha_{j}", "alpha", i, "deg"), ParamInfo(f"d_{j}", "d", i, "mm"),
                ParamInfo(f"beta_{j}", "beta", i, "deg")]
    out += [ParamInfo(f"c_{i + 1}", "c", i, "rad/(N m)") for i in range(n)]
    out += [ParamInfo(f"{t}_{j}", t, j - 1, "deg") for j in sorted(set(harmonics)) for t in HARMONICS]
    for j in positions:
        out += [ParamInfo(f"fixture_{j}_{k}", "fixture", int(j), "mm") for k in "xyz"]
    return out


def structural_fixed(robot, tool_mm, positions=()) -> dict[str, str]:
    """Parameters held fixed by the structural rules, with the reason (for the report)."""
    n = robot.n
    fixed = {"dtheta_1": "combined with the base rotation about z0 (base_c)",
             "d_1": "combined with the base height (base_z)",
             f"d_{n}": "combined with tool_z", f"a_{n}": "combined with tool_x",
             f"alpha_{n}": f"combined with dtheta_{n} and the tool", f"beta_{n}": f"combined with dtheta_{n} and the tool",
             "c_1": "joint 1 carries no gravity torque"}
    if abs(float(tool_mm[0])) > 1e-6 or abs(float(tool_mm[1])) > 1e-6:
        fixed["tool_y"] = f"held 0: the rod's twist about z{n} is dtheta_{n} (contract)"
    for j in positions:
        for k in "xyz":
            fixed[f"fixture_{j}_{k}"] = "the recorded fixture pose is trusted (free it when a diagnosis points at it)"
    parallel = set(robot.parallel_rows())
    for i in range(n - 1):
        if i in parallel:
            fixed[f"d_{i + 1}"] = f"joint {i + 1} is parallel to joint {i + 2}: beta_{i + 1} instead (d_{i + 1} " \
                                  f"combined with d_{i + 2})"
        else:
            fixed[f"beta_{i + 1}"] = "held 0 (Hayati's beta is used only between parallel joints)"
    return fixed


def apply(base: ModelParams, infos: list[ParamInfo], x_internal: np.ndarray) -> ModelParams:
    """Model parameters: ``base`` plus the internal vector (errors for DH rows, absolute for c, base, tool)."""
    th, d, a, al, be = (base.theta_offset.copy(), base.d.copy(), base.a.copy(), base.alpha.copy(),
                        base.beta.copy())
    c, bp, tool, h = base.c.copy(), base.base.copy(), base.tool.copy(), base.h.copy()
    for info, v in zip(infos, x_internal):
        s = INTERNAL_SCALE[info.unit]
        val = v / s
        k, i = info.kind, info.index
        if k == "dtheta":
            th[i] += np.deg2rad(val)
        elif k == "d":
            d[i] += val
        elif k == "a":
            a[i] += val
        elif k == "alpha":
            al[i] += np.deg2rad(val)
        elif k == "beta":
            be[i] += np.deg2rad(val)
        elif k == "c":
            c[i] += val
        elif k in HARMONICS:
            h[i, list(HARMONICS).index(k)] += np.deg2rad(val)
        elif k == "base_t":
            bp[i] += val
        elif k == "base_r":
            bp[3 + i] += val
        elif k == "tool":
            tool["xyz".index(info.name[-1])] += val
        elif k == "fixture":
            pass                                        # applied to the measurements, not the model
    return ModelParams(th, d, a, al, be, c, bp, tool, h, base.h_ref)
