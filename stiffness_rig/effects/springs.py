"""Rotational springs on the rod: the C_F increments a compliant joint adds (shared by the joint and torsion
effects, in the simulator and the diagnosis), and the candidate places of such joints on a rod."""
from __future__ import annotations

import numpy as np

from rodlab.layout import layout

__all__ = ["spring_matrices", "spring_compliance", "spring_columns", "joint_places"]


def spring_matrices(point_T, axis_T) -> tuple[np.ndarray, np.ndarray]:
    """C_F increments [mm/N] per unit bending and torsion compliance [rad/(N mm)] of a rotational spring at
    ``point_T`` (in {T}) on a member along ``axis_T``.

    A tip force F makes a moment (0 - point) x F about the spring; each compliant rotation axis e with
    compliance s adds ``s (e x r)(e x r)^T`` with r from the spring to the ball centre (origin of {T}): the two
    axes across the member bend, the member axis twists.
    """
    r = -np.asarray(point_T, float)
    t = np.asarray(axis_T, float) / np.linalg.norm(axis_T)
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    b1 = np.cross(t, helper)
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(t, b1)
    Cb = sum(np.outer(np.cross(e, r), np.cross(e, r)) for e in (b1, b2))
    Ct = np.outer(np.cross(t, r), np.cross(t, r))
    return Cb, Ct


def spring_compliance(point_T_mm, axis, s_bend: float, s_torsion: float) -> np.ndarray:
    """Extra C_F [mm/N] of a spring with bending ``s_bend`` and torsion ``s_torsion`` [rad/(N mm)]."""
    Cb, Ct = spring_matrices(point_T_mm, axis)
    return s_bend * Cb + s_torsion * Ct


def spring_columns(data, point_T, axis_T) -> np.ndarray:
    """Columns (n, 2) for a spring (bending, torsion [rad/(N mm)]): the extra displacement of each sample's
    component under its load."""
    Cb, Ct = spring_matrices(point_T, axis_T)
    return np.column_stack([Cb[data.comp, data.axis] * data.F, Ct[data.comp, data.axis] * data.F])


def joint_places(tool_mm, design=None) -> dict:
    """Candidate places of a compliant joint, in {T}: {location: (point [mm], member axis)} for
    ``flange_clamp``, ``ring_1`` and ``pipe_II`` (mid-length). From the design's layout when given; else an
    L-rod with pipe I along z and pipe II towards the ball, guessed from the tool vector."""
    tool = np.asarray(tool_mm, float)
    if design is not None:
        segs = layout(design)
        pts = {"flange_clamp": (segs[0].start_F - tool, segs[0].direction)}
        ring1 = [s for s in segs if any(str(l.part) == "ring_1" for l in s.layers)]
        if ring1:
            pts["ring_1"] = (ring1[0].point([ring1[0].length_mm / 2])[0] - tool, ring1[0].direction)
        p2 = [s for s in segs if any(str(l.part) == "pipe_II" for l in s.layers)]
        if p2:
            s = p2[len(p2) // 2]
            pts["pipe_II"] = (s.point([s.length_mm / 2])[0] - tool, s.direction)
        return pts
    L1 = tool[2] if tool[0] > 0 else tool[2] / 2
    u2 = tool - np.array([0.0, 0.0, L1])
    u2 = u2 / max(np.linalg.norm(u2), 1e-9)
    return {"flange_clamp": (-tool, np.array([0.0, 0.0, 1.0])),
            "ring_1": (np.array([0.0, 0.0, 0.78 * L1]) - tool, np.array([0.0, 0.0, 1.0])),
            "pipe_II": (np.array([0.0, 0.0, L1]) + 0.5 * np.linalg.norm(tool - [0, 0, L1]) * u2 - tool, u2)}
