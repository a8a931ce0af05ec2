"""Where a plane view's part labels go and how many tick labels each axis of its bounds gets (pure geometry, the
renderer's (:mod:`rodlab.core.view3d`) choices, testable without it)."""
from __future__ import annotations

import numpy as np

__all__ = ["grouped_labels", "tick_counts", "LABEL_MERGE"]

#: part labels whose centres lie closer than this share of the picture's extent in the view are one label
LABEL_MERGE = 0.06


def grouped_labels(centres: dict, direction, up, names_shown: dict | None = None) -> tuple:
    """(points (k, 3), texts) of the part labels in a view along ``direction`` (towards the camera) with ``up``:
    parts whose centres fall within :data:`LABEL_MERGE` of the picture's extent of each other are one label, "ball
    holder, ball" (a designer trial: the renderer had dropped the ball's label under the ball holder's, and drawn
    ring 2's over the ball); ``names_shown`` {part: its label} (default: the part's name)."""
    shown = names_shown or {}
    w = np.asarray(direction, float) / np.linalg.norm(direction)
    u = np.cross(up, w)
    u = u / np.linalg.norm(u) if np.linalg.norm(u) > 1e-9 else np.array([1.0, 0.0, 0.0])
    v = np.cross(w, u)
    names = list(centres)
    xy = np.array([[centres[n] @ u, centres[n] @ v] for n in names])
    tol = LABEL_MERGE * max(float(np.ptp(xy, axis=0).max()), 1e-9)
    groups: list = []
    for i in range(len(names)):
        home = next((g for g in groups if np.linalg.norm(xy[i] - xy[g].mean(axis=0)) < tol), None)
        if home is not None:
            home.append(i)
        else:
            groups.append([i])
    points = np.array([np.mean([centres[names[i]] for i in g], axis=0) for g in groups])
    return points, [", ".join(shown.get(names[i], names[i]) for i in g) for g in groups]


def tick_counts(sets) -> tuple:
    """Labels per axis of the bounds: 2 on an axis less than a fifth of the widest (a 45 mm tube's five labels had
    overlapped into one smear beside a 950 mm rod, a designer trial), else 5."""
    pts = np.concatenate([np.asarray(ts.vertices, float) for ts in sets])
    extent = np.ptp(pts, axis=0)
    return tuple(2 if e < 0.2 * extent.max() else 5 for e in extent)
