"""Natural frequencies: the frame model (lumped masses on the beam chain) against the solid (scikit-fem)."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import mass_properties, resolve_design

pytest.importorskip("gmsh")
pytestmark = pytest.mark.cad

#: stated tolerance of the frame model's first three frequencies against the solid (docs/study.md)
FRAME_MODAL_TOLERANCE = 0.03


@pytest.fixture(scope="module")
def steel_half():
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod4")
    return d, mesh_rod(d, size_mm=14.0, half=True)


def test_frame_frequencies_match_the_solid(steel_half):
    """The study's frame frequencies (rod 4#: 300-450 mm steel rod, bend, sleeves, ball) are within the stated
    tolerance of the solid's consistent-mass modal analysis; the first pair is one bending mode in the bend
    plane and one across it (symmetric and antisymmetric about the plane)."""
    from rodlab.fea.modal import frame_frequencies
    from rodlab.fea.modal_solid import solid_frequencies
    d, rm = steel_half
    solid = solid_frequencies(d, rm, modes=3)
    frame = frame_frequencies(d, modes=3)
    np.testing.assert_allclose(frame, solid.frequencies_Hz, rtol=FRAME_MODAL_TOLERANCE)
    assert set(solid.symmetric[:2].tolist()) == {True, False}
    assert np.all(np.diff(solid.frequencies_Hz) >= 0)
    assert solid.mass_kg == pytest.approx(mass_properties(d).mass_kg, rel=0.02)   # the meshed rod


def test_half_mesh_spectrum_equals_the_mirrored_whole(steel_half):
    """Symmetric and antisymmetric half problems together give the whole rod's spectrum."""
    from rodlab.fea.modal_solid import solid_frequencies
    d, rm = steel_half
    half = solid_frequencies(d, rm, modes=4)
    whole = solid_frequencies(d, rm.mirrored(), modes=4)
    np.testing.assert_allclose(half.frequencies_Hz, whole.frequencies_Hz, rtol=1e-6)
    assert half.mass_kg == pytest.approx(whole.mass_kg, rel=1e-12)


def test_a_heavier_ball_lowers_the_first_frequency(steel_half):
    """Denser tip: the fundamental drops, as m^-1/2 for a tip-dominated cantilever mode (bounded check)."""
    from dataclasses import replace

    from rodlab.fea.modal_solid import solid_frequencies
    from rodlab.core.materials import Material
    d, rm = steel_half
    heavy = replace(d, ball=replace(d.ball, material=Material("heavy", 370.0, 0.22, 4 * 3900.0)))
    f0 = solid_frequencies(d, rm, modes=1).frequencies_Hz[0]
    f1 = solid_frequencies(heavy, rm, modes=1).frequencies_Hz[0]
    assert 0.5 * f0 < f1 < 0.95 * f0


def test_modes_must_be_positive(steel_half):
    from rodlab.fea import FeaError
    from rodlab.fea.modal_solid import solid_frequencies
    d, rm = steel_half
    with pytest.raises(FeaError, match="modes"):
        solid_frequencies(d, rm, modes=0)
