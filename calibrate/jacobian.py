"""Analytic Jacobian of ball positions in {W} with respect to the calibration parameters."""
from __future__ import annotations

import numpy as np

from rodlab.core.frames import rot_x, rot_y

from .kinematics import HARMONICS, Frames, cross3, harmonic_basis
from .params import INTERNAL_SCALE, ParamInfo

__all__ = ["position_jacobian"]


def position_jacobian(fr: Frames, tau: np.ndarray, infos: list[ParamInfo], base_pose: np.ndarray,
                      group: np.ndarray | None = None) -> np.ndarray:
    """d (p^W - fixture offset) / d x (internal units), shape=(N, 3, P); ``group``: clamping position per point."""
    N = fr.p0.shape[0]
    R = fr.R_W0
    p0 = fr.p0
    out = np.zeros((N, 3, len(infos)))
    n = fr.z_prev.shape[1]
    Rn = fr.T[:, n, :3, :3]
    a_rad, b_rad = np.deg2rad(base_pose[3]), np.deg2rad(base_pose[4])
    axes_base = [np.array([1.0, 0.0, 0.0]), rot_x(a_rad) @ np.array([0.0, 1.0, 0.0]),
                 rot_x(a_rad) @ rot_y(b_rad) @ np.array([0.0, 0.0, 1.0])]
    for k, info in enumerate(infos):
        i = info.index
        kind = info.kind
        if kind in ("dtheta", "c") or kind in HARMONICS:
            col = cross3(fr.z_prev[:, i], p0 - fr.o_prev[:, i])
            if kind == "c":
                col = col * tau[:, i:i + 1]
            elif kind in HARMONICS:
                basis = fr.harmonic if fr.harmonic is not None else harmonic_basis(fr.q)
                col = col * basis[:, i, list(HARMONICS).index(kind), None]
        elif kind == "d":
            col = fr.z_prev[:, i]
        elif kind == "a":
            col = fr.xA[:, i]
        elif kind == "alpha":
            col = cross3(fr.xA[:, i], p0 - fr.o_i[:, i])
        elif kind == "beta":
            col = cross3(fr.yB[:, i], p0 - fr.o_i[:, i])
        elif kind == "tool":
            col = Rn[:, :, "xyz".index(info.name[-1])]
        elif kind == "fixture":
            if group is not None:
                out[group == i, "xyz".index(info.name[-1]), k] = -1.0
            continue
        elif kind == "base_t":
            out[:, :, k] = np.eye(3)[i] / INTERNAL_SCALE[info.unit]
            continue
        elif kind == "base_r":
            out[:, :, k] = cross3(axes_base[i], fr.pW - fr.t_W0) * (np.pi / 180.0) / INTERNAL_SCALE[info.unit]
            continue
        else:  # pragma: no cover
            raise ValueError(kind)
        scale = np.pi / 180.0 if kind in ("dtheta", "alpha", "beta") or kind in HARMONICS else 1.0
        out[:, :, k] = (col @ R.T) * scale / INTERNAL_SCALE[info.unit]
    return out
