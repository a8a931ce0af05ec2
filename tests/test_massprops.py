"""Mass properties from the parts: hand formulas, torus centroid, totals."""
from __future__ import annotations

import math

import numpy as np
import pytest

from rodlab import Part, mass_properties, part_mass_properties

from conftest import legacy_design


def test_part_masses_match_hand_formulas():
    d = legacy_design("rod1")     # the hand formulas below use its 25 x 2 tube and parts
    parts = part_mass_properties(d)
    ann = lambda do, di: math.pi / 4 * (do ** 2 - di ** 2)  # noqa: E731
    cf, st, al = 1550e-9, 8000e-9, 2810e-9
    assert parts[Part.PIPE_HOLDER].mass_kg == pytest.approx(ann(40, 25) * 40 * al, rel=1e-9)
    assert parts[Part.RING_1].mass_kg == pytest.approx(ann(32, 25) * 50 * al, rel=1e-9)
    assert parts[Part.BEND].mass_kg == pytest.approx(ann(25, 21) * 40 * math.pi / 2 * st, rel=1e-9)
    assert parts[Part.PIPE_I].mass_kg == pytest.approx(ann(25, 21) * 260 * cf, rel=1e-9)
    assert parts[Part.PIPE_II].mass_kg == pytest.approx(ann(25, 21) * (450 - 40 - 15 - 20) * cf, rel=1e-9)
    h = 15 - math.sqrt(15 ** 2 - 10 ** 2)            # seat depth of the 20 mm stud in the 30 mm ball
    plug = ann(21, 0) * 10.5                          # plug in pipe II's bore, half the bore long
    assert parts[Part.BALL_HOLDER].mass_kg == pytest.approx((ann(20, 0) * (20 + h) + plug) * al, rel=1e-9)
    cap = math.pi * h * h * (45 - h) / 3
    assert parts[Part.BALL].mass_kg == pytest.approx((4 / 3 * math.pi * 15 ** 3 - cap) * 3950e-9, rel=1e-12)


def test_bend_centroid_is_the_swept_annulus_centroid():
    """Quarter torus: centroid at (R^2 + I/A)/R * 2 sqrt(2)/pi from the bend centre, on the bisector."""
    d = legacy_design("rod1")     # the hand formulas below use its 25 x 2 tube and parts
    bend = part_mass_properties(d)[Part.BEND]
    R = 40.0
    IA = (12.5 ** 2 + 10.5 ** 2) / 4
    dist = (R * R + IA) / R * 2 * math.sqrt(2) / math.pi
    centre_F = np.array([R, 0.0, 260.0])
    com_F = bend.com_T_mm + d.tool_mm
    v = com_F - centre_F
    assert np.linalg.norm(v) == pytest.approx(dist, rel=1e-9)
    assert v[0] == pytest.approx(-v[2], rel=1e-9) and v[0] < 0


def test_total_is_parallel_axis_sum_and_physical():
    d = legacy_design("rod1")     # the hand formulas below use its 25 x 2 tube and parts
    total = mass_properties(d)
    parts = part_mass_properties(d)
    assert total.mass_kg == pytest.approx(sum(p.mass_kg for p in parts.values()))
    I = total.inertia_kg_mm2
    np.testing.assert_allclose(I, I.T, atol=1e-9)
    ev = np.linalg.eigvalsh(I)
    assert ev.min() > 0 and ev[0] + ev[1] >= ev[2] * (1 - 1e-9)   # triangle inequality of principal moments
    assert total.com_T_mm[1] == pytest.approx(0.0, abs=1e-9)


def test_cylinder_inertia_exact():
    d = legacy_design("rod1")     # the hand formulas below use its 25 x 2 tube and parts
    ph = part_mass_properties(d)[Part.PIPE_HOLDER]
    m, ro, ri, L = ph.mass_kg, 20.0, 12.5, 40.0
    np.testing.assert_allclose(np.diag(ph.inertia_kg_mm2),
                               [m * (3 * (ro ** 2 + ri ** 2) + L ** 2) / 12] * 2 + [m * (ro ** 2 + ri ** 2) / 2],
                               rtol=1e-9)
