"""geometry/: CAD assembly vs the analytic core, exports, refusals, and the FEA mesh."""
from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("build123d")
pytest.importorskip("gmsh")

from rodlab.geometry import GeometryError, build_cad, mesh_rod  # noqa: E402
from rodlab import Part, mass_properties, part_mass_properties, resolve_design  # noqa: E402
from rodlab.core.design_io import design_from_dict  # noqa: E402
from conftest import legacy_design  # noqa: E402

pytestmark = pytest.mark.cad


def _offgrid(**over):
    data = {"format": "rodlab.rod/1", "name": "off", "L1_mm": 260.0, "L2_mm": 410.0, "gamma_deg": 118.0,
            "tube": {"material": "cfrp", "outer_diameter_mm": 22.0, "wall_mm": 1.5},
            "bend": {"material": "ti_6al4v", "radius_mm": 45.0}}
    data.update(over)
    return design_from_dict(data)


@pytest.mark.parametrize("name", ["rod1", "rod2", "rod3", "rod4", "rod5", "rod6", "offgrid"])
def test_cad_mass_properties_match_analytic(name):
    d = _offgrid() if name == "offgrid" else resolve_design(name)
    cad = build_cad(d)
    assert set(cad.solids) == set(part_mass_properties(d))
    ana = part_mass_properties(d)
    for part, mp in cad.mass_properties().items():
        a = ana[part]
        assert mp.mass_kg == pytest.approx(a.mass_kg, rel=5e-3), part
        assert np.linalg.norm(mp.com_T_mm - a.com_T_mm) < 5e-3 * max(np.linalg.norm(a.com_T_mm), 10.0), part
        np.testing.assert_allclose(mp.inertia_kg_mm2, a.inertia_kg_mm2, rtol=5e-3,
                                   atol=5e-3 * np.abs(a.inertia_kg_mm2).max())
    tot, ana_tot = cad.total_mass_properties(), mass_properties(d)
    assert tot.mass_kg == pytest.approx(ana_tot.mass_kg, rel=5e-3)
    np.testing.assert_allclose(tot.com_T_mm, ana_tot.com_T_mm, atol=0.5)


def test_exports(tmp_path):
    cad = build_cad(resolve_design("rod1"))
    step = cad.export_step(tmp_path / "rod.step").read_text(errors="replace")
    for part in Part:
        assert f"PRODUCT('{part.value}'" in step
    assert "COLOUR_RGB" in step
    stl = cad.export_stl(tmp_path / "rod.stl")
    assert stl.stat().st_size > 10_000
    rep = cad.mass_report()
    assert set(rep["parts"]) == {p.value for p in Part} and rep["total"]["mass_kg"] > 0.4


def test_renders_four_legible_views(tmp_path):
    from rodlab.geometry import render_views
    import matplotlib.image as mpimg
    paths = render_views(build_cad(resolve_design("rod1")), tmp_path)
    assert [p.name for p in paths] == ["view_iso.png", "view_xz.png", "view_xy.png", "view_yz.png"]
    for p in paths:
        img = mpimg.imread(p)
        assert img.shape[0] > 150 and img.shape[1] > 600
        dark = (img[..., :3].mean(axis=-1) < 0.3).mean()   # the black carbon tubes are drawn
        assert dark > 0.01, p


def test_folded_design_is_refused_naming_part_and_dimension():
    # the analytic rules keep the tubes 2 R apart for any gamma; a huge flange adapter is what can collide
    d = _offgrid(gamma_deg=30.0, L1_mm=260.0, L2_mm=290.0, bend={"radius_mm": 33.0},
                 pipe_holder={"outer_diameter_mm": 320.0, "length_mm": 40.0})
    with pytest.raises(GeometryError) as ei:
        build_cad(d)
    assert ei.value.key == "gamma_deg" and "overlaps" in str(ei.value)


def test_gmsh_kernel_refuses_the_folded_design_too():
    """The mesh builds its parts in gmsh's kernel (no build123d): the same overlap check, the same message."""
    d = _offgrid(gamma_deg=30.0, L1_mm=260.0, L2_mm=290.0, bend={"radius_mm": 33.0},
                 pipe_holder={"outer_diameter_mm": 320.0, "length_mm": 40.0})
    with pytest.raises(GeometryError) as ei:
        mesh_rod(d, size_mm=20.0)
    assert ei.value.key == "gamma_deg" and "overlaps" in str(ei.value)


def test_both_kernels_mesh_the_same_half_rod():
    """gmsh's own OCC parts and the build123d solids are the same geometry: equal part volumes of the half
    mesh, the same parts and surfaces, nearly the same mesh."""
    d = resolve_design("rod3")
    a = mesh_rod(d, size_mm=10.0, half=True)
    b = mesh_rod(d, size_mm=10.0, half=True, kernel="build123d")
    assert a.parts == b.parts
    va, vb = a.volume_by_part(), b.volume_by_part()
    for part in va:
        assert va[part] == pytest.approx(vb[part], rel=1e-4), part
    assert a.stats["nodes"] == pytest.approx(b.stats["nodes"], rel=0.02)
    assert a.symmetry_facets.size == pytest.approx(b.symmetry_facets.size, rel=0.05)
    with pytest.raises(GeometryError, match="kernel"):
        mesh_rod(d, kernel="cadquery")


@pytest.fixture(scope="module")
def rod1_mesh():
    return mesh_rod(legacy_design("rod1"))


def test_mesh_parts_quality_and_volumes(rod1_mesh):
    rm = rod1_mesh
    assert set(rm.parts) == set(Part)
    assert rm.min_quality > 0.05                       # no inverted or degenerate elements
    cad = build_cad(legacy_design("rod1"))
    for part, vol in rm.volume_by_part().items():
        assert vol == pytest.approx(cad.solids[part].volume, rel=5e-3), part
    assert rm.flange_facets.size > 50 and rm.ball_facets.size > 100


def test_mesh_is_conformal_and_connected(rod1_mesh):
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    m = rod1_mesh.mesh
    # no coincident duplicate vertices (a non-conformal interface would duplicate them)
    rounded = np.round(m.p.T, 6)
    assert np.unique(rounded, axis=0).shape[0] == m.p.shape[1]
    # one connected body through shared vertices
    ne = m.t.shape[1]
    rows = np.repeat(np.arange(ne), 4)
    inc = coo_matrix((np.ones(rows.size), (rows, m.t.T.ravel())), shape=(ne, m.p.shape[1])).tocsr()
    n, _ = connected_components(inc @ inc.T, directed=False)
    assert n == 1
    # interfaces: ring_1 elements share vertices with pipe_I elements
    v_ring = set(m.t[:, rod1_mesh.elements_of(Part.RING_1)].ravel())
    v_pipe = set(m.t[:, rod1_mesh.elements_of(Part.PIPE_I)].ravel())
    assert len(v_ring & v_pipe) > 50


def test_tube_axis_follows_the_centreline(rod1_mesh):
    rm = rod1_mesh
    d = resolve_design("rod1")
    ax1 = rm.tube_axis[rm.elements_of(Part.PIPE_I)]
    np.testing.assert_allclose(ax1, np.broadcast_to([0, 0, 1.0], ax1.shape), atol=1e-12)
    ax2 = rm.tube_axis[rm.elements_of(Part.PIPE_II)]
    np.testing.assert_allclose(ax2, np.broadcast_to(d.pipe_II_direction, ax2.shape), atol=1e-12)
    axb = rm.tube_axis[rm.elements_of(Part.BEND)]
    assert axb[:, 0].min() < 0.2 and axb[:, 0].max() > 0.8     # turns from +z to +x along the bend


def test_mesh_file_and_determinism(tmp_path, rod1_mesh):
    a = mesh_rod(legacy_design("rod1"), msh_path=tmp_path / "a.msh")
    assert a.sha256 == rod1_mesh.sha256 and a.stats["nodes"] == rod1_mesh.stats["nodes"]
    text = (tmp_path / "a.msh").read_text()
    assert text.startswith("$MeshFormat\n4.1")
    for name in ["flange_face", "ball"] + [p.value for p in Part]:
        assert f'"{name}"' in text


def test_first_order_mesh_and_bad_size():
    d = resolve_design("rod5")
    rm = mesh_rod(d, size_mm=3.0, order=1)
    assert rm.mesh.t.shape[0] == 4 and rm.min_quality > 0
    with pytest.raises(GeometryError, match="size"):
        mesh_rod(d, size_mm=-1.0)


def test_grading_refines_the_tubes_not_the_holders():
    """Graded mesh: fine at the section changes inside the tubes, the bend at most bend_factor * size, parts
    away from the tubes at the size; bad grading tuples are refused naming the key."""
    d = resolve_design("rod1")
    uni = mesh_rod(d, size_mm=8.0, half=True)
    grad = mesh_rod(d, size_mm=8.0, grading=(0.4, 0.3, 0.6), half=True)
    n = lambda rm, p: rm.elements_of(p).size  # noqa: E731
    for p in (Part.PIPE_I, Part.PIPE_II):
        assert n(grad, p) > 1.2 * n(uni, p), p
    assert n(grad, Part.BEND) > 1.8 * n(uni, Part.BEND)                 # graded and at most 0.6 x size
    assert n(grad, Part.BALL) < 1.1 * n(uni, Part.BALL)                 # no face shared with a tube: size
    for bad in [(0.0, 0.3), (0.4,), (0.4, 0.3, 1.5), ("a", 0.3)]:
        with pytest.raises(GeometryError) as ei:
            mesh_rod(d, size_mm=8.0, grading=bad)
        assert ei.value.key == "grading"
