"""Closed-form compliance: paper formulas, cantilever limits, reciprocity, scaling, a hand case."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rodlab import G0, calc_compliance, load_design, paper_compliance, resolve_design
from rodlab.core.calc import BendModel
from rodlab.core.design_io import design_from_dict

from conftest import ROD1, legacy_design


def _design(**over):
    data = {"format": "rodlab.rod/1", "name": "t", "L1_mm": 300.0, "L2_mm": 450.0, "gamma_deg": 90.0,
            "tube": {"material": "steel_304", "outer_diameter_mm": 20.0, "wall_mm": 2.0},
            "bend": {"radius_mm": 40.0},
            "rings": {"length_mm": 0.0}, "pipe_holder": {"length_mm": 0.0}, "ball_holder": {"length_mm": 0.0}}
    for k, v in over.items():
        if isinstance(v, dict):
            data.setdefault(k, {}).update(v)
        else:
            data[k] = v
    return design_from_dict(data)


def test_pipes_only_equals_paper_eqs_15_17():
    for l1, l2 in [(300, 450), (150, 525), (375, 600)]:
        d = _design(L1_mm=float(l1), L2_mm=float(l2))
        CF, Cg = calc_compliance(d, pipes_only=True, axial=False)
        PF, Pg = paper_compliance(d)
        np.testing.assert_allclose(CF, PF, rtol=1e-10, atol=1e-15)
        np.testing.assert_allclose(Cg, Pg, rtol=1e-10, atol=1e-15)


def test_paper_compliance_refuses_other_gamma():
    with pytest.raises(ValueError, match="gamma = 90"):
        paper_compliance(_design(gamma_deg=120.0))


def test_straight_cantilever_limit_hand_computed():
    """gamma = 180, no parts: a uniform tube bonded into the ball's flat seat, load at the ball centre L."""
    d = _design(gamma_deg=180.0)
    CF, Cg = calc_compliance(d)
    od, wall = 20.0, 2.0
    E = 193e3
    I = math.pi / 64 * (od ** 4 - (od - 2 * wall) ** 4)
    A = math.pi / 4 * (od ** 2 - (od - 2 * wall) ** 2)
    L, r = 750.0, 15.0
    zc = math.sqrt(r * r - (od / 2) ** 2)   # the tube ends at the seat, zc before the centre
    Lt = L - zc
    bend_xx = (L ** 3 - zc ** 3) / (3 * E * I)
    np.testing.assert_allclose(np.diag(CF), [bend_xx, bend_xx, Lt / (E * A)], rtol=1e-9)
    assert abs(CF[0, 1]) + abs(CF[0, 2]) + abs(CF[1, 2]) < 1e-12
    # gravity: uniform tube load w over [0, Lt]; the truncated ball (sphere minus the cap beyond the seat)
    # as a point weight at its centre of mass, which lies beyond the centre by |a_c|
    w = A * 8000e-9 * G0                          # N/mm per g0
    h = r - zc
    v_cap = math.pi * h * h * (3 * r - h) / 3
    a_cap = 3 * (2 * r - h) ** 2 / (4 * (3 * r - h))   # cap centroid from the centre
    v = 4 / 3 * math.pi * r ** 3 - v_cap
    m = v * 3950e-9 * G0                          # N per g0
    Lc = L + v_cap * a_cap / v                    # centre of mass of the truncated ball
    # virtual work: unit load at L, real loads w on [0, Lt] and m at Lc
    from scipy.integrate import quad
    dist = quad(lambda s: (L - s) * w * (Lt - s) ** 2 / 2, 0, Lt)[0] / (E * I)
    expect = dist + m * quad(lambda s: (L - s) * (Lc - s), 0, Lt)[0] / (E * I)
    np.testing.assert_allclose(Cg[0, 0], expect, rtol=1e-9)
    np.testing.assert_allclose(Cg[2, 2], (w * Lt ** 2 / 2 + m * Lt) / (E * A), rtol=1e-9)


def test_maxwell_betti_symmetry_any_gamma():
    for gamma in (30.0, 60.0, 90.0, 135.0, 179.0):
        d = load_design(ROD1) if gamma == 90 else _design(gamma_deg=gamma)
        CF, _ = calc_compliance(d, shear=True)
        np.testing.assert_allclose(CF, CF.T, rtol=1e-12, atol=1e-15)
        assert np.all(np.linalg.eigvalsh(CF) > 0)


def test_scaling_with_modulus():
    d1 = _design()
    d2 = _design(materials={"soft": {"E_GPa": 96.5, "nu": 0.29, "density_kg_m3": 8000.0}},
                 tube={"material": "soft"})
    c1, g1 = calc_compliance(d1, pipes_only=True)
    c2, g2 = calc_compliance(d2, pipes_only=True)
    np.testing.assert_allclose(c2, 2 * c1, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(g2, 2 * g1, rtol=1e-9, atol=1e-15)


def test_czz_scales_as_L2_cubed_when_L1_vanishes():
    vals = []
    for l2 in (3000.0, 6000.0):   # L1 / L2 <= 1 %: the L1 term is a <= 2 % correction
        d = _design(L1_mm=30.0, L2_mm=l2, bend={"radius_mm": 30.0})
        CF, _ = calc_compliance(d, pipes_only=True, axial=False)
        vals.append(CF[2, 2])
    assert vals[1] / vals[0] == pytest.approx(8.0, rel=0.02)
    assert vals[1] / vals[0] < 8.0   # and from below: the L1 L2^2 term grows only as L2^2


def test_tip_mass_only_gives_Cg_equal_m_g0_CF():
    """With (almost) massless tubes and a needle-thin stud (no seat), gravity acts on the ball alone:
    C_g = m_ball g0 C_F."""
    d = _design(materials={"light": {"E_GPa": 193.0, "nu": 0.29, "density_kg_m3": 1e-9}},
                tube={"material": "light"}, ball_holder={"material": "light", "outer_diameter_mm": 0.2,
                                                          "length_mm": 10.0})
    CF, Cg = calc_compliance(d)
    m = 4 / 3 * math.pi * 15.0 ** 3 * 3950e-9
    np.testing.assert_allclose(Cg, m * G0 * CF, rtol=1e-6, atol=1e-14)


def test_corner_bend_reproduces_contract_example(examples):
    """The example compliance file is a sharp-corner Euler-Bernoulli frame without axial terms."""
    ref = json.loads((examples / "rod1.compliance.json").read_text())
    CF, _ = calc_compliance(load_design(examples / "rods" / "rod1.rod.toml"), bend=BendModel.CORNER, axial=False)
    np.testing.assert_allclose(CF, np.array(ref["C_F_mm_per_N"]), rtol=1e-3, atol=1e-7)


def test_arc_bend_is_softer_in_torsion_than_corner_but_close():
    d = legacy_design("rod1")        # 25 x 2 carbon tube: the bend's share of c22 / c33 stays below 5 %
    arc, _ = calc_compliance(d)
    corner, _ = calc_compliance(d, bend=BendModel.CORNER)
    assert np.all(np.abs(np.diag(arc) / np.diag(corner) - 1) < 0.05)
    assert arc[2, 2] < corner[2, 2]  # the arc shortens the lever of pipe II's moment over the bend


def test_vectorised_centreline_matches_segments():
    """The unit-load integrator's array form of the centreline equals Segment.point / tangent, and its exact
    first moments equal a fine numerical quadrature of the positions."""
    from rodlab.core.calc import Centreline
    from rodlab.core.layout import SegmentKind, layout
    segs = layout(resolve_design("rod1"))
    assert any(s.kind is SegmentKind.ARC for s in segs)
    cl = Centreline(segs)
    for k, seg in enumerate(segs):
        u = np.linspace(0.0, seg.length_mm, 7)
        idx = np.full(u.size, k)
        np.testing.assert_allclose(cl.point(idx, u), seg.point(u), atol=1e-9)
        np.testing.assert_allclose(cl.tangent(idx, u), seg.tangent(u), atol=1e-12)
        x, w = np.polynomial.legendre.leggauss(40)
        s = 0.5 * (x + 1.0) * (seg.length_mm - u[2]) + u[2]
        ref = (0.5 * w * (seg.length_mm - u[2])) @ seg.point(s)
        np.testing.assert_allclose(cl.point_integral(idx[:1], u[2:3])[0], ref, rtol=1e-10, atol=1e-8)
