"""Rotational springs on the rod: the C_F increments a compliant joint adds (shared by the joint and torsion
effects, in the simulator and the diagnosis), and the candidate places of such joints on a rod."""
from __future__ import annotations

import numpy as np

from rodlab.core.joint_springs import design_joint_places, spring_matrices

__all__ = ["spring_matrices", "spring_compliance", "spring_columns", "joint_places"]


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
        return {k: (p.point_T_mm, p.axis_T) for k, p in design_joint_places(design).items()}
    L1 = tool[2] if tool[0] > 0 else tool[2] / 2
    u2 = tool - np.array([0.0, 0.0, L1])
    u2 = u2 / max(np.linalg.norm(u2), 1e-9)
    return {"flange_clamp": (-tool, np.array([0.0, 0.0, 1.0])),
            "ring_1": (np.array([0.0, 0.0, 0.78 * L1]) - tool, np.array([0.0, 0.0, 1.0])),
            "pipe_II": (np.array([0.0, 0.0, L1]) + 0.5 * np.linalg.norm(tool - [0, 0, L1]) * u2 - tool, u2)}
