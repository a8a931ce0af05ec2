"""The plane views' part labels and bound ticks (rodlab.core.view3d, pure geometry: no renderer needed)."""
from __future__ import annotations

import numpy as np

from rodlab.core.render3d import VIEWS, TriangleSet
from rodlab.core.view3d import _PART_LABEL
from rodlab.core.view_labels import grouped_labels, tick_counts


def test_labels_of_parts_that_fall_together_in_a_view_are_one():
    """Seen along x, ring 2, pipe II, the ball holder and the ball of an L-shaped rod sit on one spot: one label
    naming them all (a designer trial: the ball's label had been dropped, ring 2's drawn over the ball); seen
    from the side, pipe II stands alone."""
    centres = {"pipe_I": np.array([-600.0, 0, -200]), "ring_2": np.array([-480.0, 0, 0]),
               "pipe_II": np.array([-270.0, 0, 0]), "ball_holder": np.array([-30.0, 0, 0]),
               "ball": np.array([0.0, 0, 0])}
    direction, up, _ = VIEWS["yz"]
    _, texts = grouped_labels(centres, direction, up, _PART_LABEL)
    assert "ring 2, pipe II, ball holder, ball" in texts and "pipe I" in texts
    direction, up, _ = VIEWS["xz"]
    points, texts = grouped_labels(centres, direction, up, _PART_LABEL)
    assert "pipe II" in texts and "ball holder, ball" in texts and len(points) == len(texts) == 4


def test_a_narrow_axis_gets_two_tick_labels():
    rod = TriangleSet("tube", np.array([[0.0, -22.5, 0], [950, 22.5, 0], [0, 0, -350]]), np.array([[0, 1, 2]]),
                      (0.5, 0.5, 0.5))
    assert tick_counts([rod]) == (5, 2, 5)
