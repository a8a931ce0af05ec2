"""FEA fields out (``rodlab fea --fields``: .vtu / .vtp) and their pictures (``rodlab view``, rodlab.core.view3d)."""
from __future__ import annotations

import base64
import ctypes.util
import xml.etree.ElementTree as ET
import zlib

import numpy as np
import pytest

from rodlab import resolve_design
from rodlab.core.design_io import design_from_dict
from rodlab.core.enums import Part
from rodlab.core.vtkio import VTK_QUADRATIC_TETRA, VtkData, decode_strings, encode_strings, write_vtu

CASES = ("Fx", "Fy", "Fz", "gx", "gy", "gz")


def _decode(text: str, dtype) -> np.ndarray:
    """One inline binary array of rodlab.core.vtkio (UInt64 header [1, n, n, compressed n], zlib), decoded by hand."""
    head = base64.b64decode(text[:44])                    # 32 header bytes -> 44 base64 characters
    n_blocks, raw, last, comp = np.frombuffer(head, "<u8")
    assert n_blocks == 1 and raw == last
    data = zlib.decompress(base64.b64decode(text[44:]))
    assert len(data) == raw
    return np.frombuffer(data, dtype)


def test_vtu_writer_writes_what_vtk_documents(tmp_path):
    """The XML read with the standard library alone: the numbers written are the numbers read, the quadratic
    tetrahedron keeps its 10 nodes, names are zero-terminated ASCII codes."""
    pts = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [.5, 0, 0], [.5, .5, 0], [0, .5, 0], [0, 0, .5],
                    [.5, 0, .5], [0, .5, .5]], float)
    disp = np.arange(30, dtype=float).reshape(10, 3) * 1e-3
    path = write_vtu(tmp_path / "one.vtu", pts, np.arange(10)[None, :], VTK_QUADRATIC_TETRA,
                     VtkData({"displacement_Fx": disp}, {"part": np.array([2])}, {"part_names": ["tube", "ball"]}))
    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid" and root.get("header_type") == "UInt64"
    arrays = {a.get("Name"): a for a in root.iter() if a.tag in ("DataArray", "Array")}
    np.testing.assert_array_equal(_decode(arrays["Points"].text, "<f8").reshape(-1, 3), pts)
    np.testing.assert_array_equal(_decode(arrays["displacement_Fx"].text, "<f8").reshape(-1, 3), disp)
    assert arrays["displacement_Fx"].get("NumberOfComponents") == "3"
    assert _decode(arrays["types"].text, "u1").tolist() == [24]
    assert _decode(arrays["offsets"].text, "<i8").tolist() == [10]
    assert _decode(arrays["part"].text, "<i8").tolist() == [2]
    assert arrays["part_names"].get("type") == "UInt8"           # texts as ASCII codes, each ended by 0
    assert _decode(arrays["part_names"].text, "u1").tobytes() == b"tube\0ball\0"
    assert not [a for a in arrays.values() if a.get("type") == "String"]     # meshio refuses String arrays
    meshio = pytest.importorskip("meshio")
    m = meshio.read(path)
    assert m.cells[0].type == "tetra10" and m.cells[0].data.tolist() == [list(range(10))]
    np.testing.assert_array_equal(m.point_data["displacement_Fx"], disp)
    assert decode_strings(m.field_data["part_names"]) == ["tube", "ball"]
    assert decode_strings(encode_strings(["Stab ü", "", "1#"])) == ["Stab ü", "", "1#"]
    with pytest.raises(ValueError, match="10 rows"):
        write_vtu(tmp_path / "bad.vtu", pts, np.arange(10)[None, :], VTK_QUADRATIC_TETRA,
                  VtkData({"u": disp[:4]}))
    assert not (tmp_path / "bad.vtu").exists()


def test_frame_centreline_ends_at_the_compliance():
    """The centreline's last point is the ball centre and moves by the frame's C_F and C_g columns; the clamp
    does not move; displacements grow along the rod."""
    from rodlab.fea import frame_compliance
    from rodlab.fea.fields import frame_centreline_fields
    d = resolve_design("rod1")
    f = frame_centreline_fields(d, n_points=120)
    points, disp = f.points_mm, f.displacement
    np.testing.assert_allclose(points[-1], d.tool_mm, atol=1e-9)
    np.testing.assert_allclose(points[0], [0.0, 0.0, 0.0], atol=1e-9)
    CF, Cg = frame_compliance(d)
    np.testing.assert_allclose(disp[-1, :, :3], CF, atol=1e-9 * np.abs(CF).max())
    np.testing.assert_allclose(disp[-1, :, 3:], Cg, atol=1e-9 * np.abs(Cg).max())
    assert np.abs(disp[0]).max() == 0.0
    uy = disp[:, 1, 1]                                 # sideways: grows monotonically from the clamp
    assert np.all(np.diff(uy) >= -1e-15) and uy[len(uy) // 2] < 0.5 * uy[-1]
    # parts along the centreline, flange to ball: a ring where it carries load, the tube in its end zones
    assert f.parts == ("pipe_holder", "pipe_I", "ring_1", "bend", "ring_2", "pipe_II", "ball_holder")
    assert f.part_index[0] == 0 and f.part_index[3 * len(f.part_index) // 4] == 5 and f.part_index[-1] == 6


def test_frame_vtp_has_the_parts_and_the_stress(tmp_path):
    """The .vtp: one poly-line per run of a part (sharing end points), cell array ``part`` naming
    ``part_names``, point arrays displacement_<case> and von_mises_<case>; rodlab view names the peak's part."""
    pv = pytest.importorskip("pyvista")
    from rodlab.fea.fields import frame_centreline_fields, write_frame_fields
    d = resolve_design("rod1")
    m = pv.read(write_frame_fields(tmp_path / "rod1.vtp", d, n_points=150))
    f = frame_centreline_fields(d, n_points=150)
    names = decode_strings(m.field_data["part_names"])
    assert tuple(names) == f.parts and m.n_points == 150
    lines = [m.get_cell(c).point_ids for c in range(m.n_cells)]
    assert lines[0][0] == 0 and lines[-1][-1] == 149 and all(a[-1] == b[0] for a, b in zip(lines[:-1], lines[1:]))
    for c, ids in enumerate(lines):
        assert f.part_index[ids[0]] == m.cell_data["part"][c]
    for k, key in enumerate(CASES):
        np.testing.assert_allclose(m.point_data[f"von_mises_{key}"], f.von_mises[:, k], rtol=1e-12)
        np.testing.assert_allclose(m.point_data[f"displacement_{key}"], f.displacement[:, :, k], rtol=1e-12)
    from rodlab.core.view3d import field_peak, read_field_view
    view = read_field_view(tmp_path / "rod1.vtp")
    i = int(np.argmax(f.von_mises[:, 1]))
    assert field_peak(view, f.von_mises[:, 1]) == (pytest.approx(f.von_mises[i, 1]), f.parts[f.part_index[i]].replace("_", " "))


def _straight_tube(material: str = "steel_304"):
    """A straight tube (D 20 mm, wall 2 mm) from the flange (z = 0) to the ball, no rings or holders."""
    return design_from_dict({"format": "rodlab.rod/1", "name": "straight", "L1_mm": 300.0, "L2_mm": 300.0,
                             "gamma_deg": 180.0, "tube": {"material": material, "outer_diameter_mm": 20.0,
                                                          "wall_mm": 2.0},
                             "rings": {"length_mm": 0.0}, "pipe_holder": {"length_mm": 0.0},
                             "ball_holder": {"length_mm": 0.0}})


def test_frame_stress_of_a_straight_tube_is_the_cantilever_closed_form(tmp_path):
    """Frame model, straight steel tube clamped at z = 0, loads at the ball centre z_b: a transverse unit force
    bends the section at z by M = (z_b - z) N mm, sigma = M r_o / I (largest at the clamp, F L r_o / I); an
    axial one gives F / A; self-weight across the tube bends it by the weight beyond z times its lever arm,
    along it stretches it by that weight over A. Written to the .vtp as von_mises_<case>."""
    from rodlab.fea.fields import frame_centreline_fields, write_frame_fields
    from rodlab.fea.frame import frame_segments
    from rodlab.core.massprops import ball_mass_properties
    from rodlab.core.units import G0
    d = _straight_tube()
    f = frame_centreline_fields(d, n_points=60)
    ro, ri = 10.0, 8.0
    A, I = np.pi * (ro ** 2 - ri ** 2), np.pi / 4 * (ro ** 4 - ri ** 4)
    z, zb = f.points_mm[:-1, 2], d.tool_mm[2]          # the last point is the ball centre (the last section's)
    np.testing.assert_allclose(f.von_mises[:-1, 0], (zb - z) * ro / I, rtol=1e-9)
    np.testing.assert_allclose(f.von_mises[:-1, 1], (zb - z) * ro / I, rtol=1e-9)
    assert f.von_mises[0, 0] == pytest.approx(zb * ro / I, rel=1e-9)       # root: F L r_o / I
    np.testing.assert_allclose(f.von_mises[:-1, 2], 1.0 / A, rtol=1e-9)
    ball = ball_mass_properties(d)
    segs = frame_segments(d)
    zc, L = ball.com_T_mm[2] + zb, segs[-1].s0_mm + segs[-1].length_mm      # the tube ends at the ball
    mu = d.material_of(Part.PIPE_I).density_kg_m3 * 1e-9 * A             # line mass [kg/mm]
    weight_beyond = G0 * (mu * (L - z) + ball.mass_kg)
    moment = G0 * (mu * (L - z) ** 2 / 2 + ball.mass_kg * (zc - z))
    np.testing.assert_allclose(f.von_mises[:-1, 3], moment * ro / I, rtol=1e-6)
    np.testing.assert_allclose(f.von_mises[:-1, 5], weight_beyond / A, rtol=1e-6)
    pv = pytest.importorskip("pyvista")
    m = pv.read(write_frame_fields(tmp_path / "straight.vtp", d, n_points=60))
    np.testing.assert_allclose(m.point_data["von_mises_Fx"], f.von_mises[:, 0], rtol=1e-12)


# --- the solid model's fields (cad extra for the mesh) -------------------------------------------------

def _solid(design, size_mm):
    pytest.importorskip("build123d")
    pytest.importorskip("gmsh")
    from rodlab.fea import solid_compliance
    from rodlab.geometry import mesh_rod
    return solid_compliance(design, mesh_rod, size_mm=size_mm, error_estimate=False, keep_displacements=True)


@pytest.fixture(scope="module")
def rod1_solid():
    from rodlab.fea.fields import solid_fields
    d = resolve_design("rod1")
    comp, res = _solid(d, 12.0)
    return d, comp, solid_fields(d, res)


@pytest.fixture(scope="module")
def rod1_vtu(rod1_solid, tmp_path_factory):
    from rodlab.fea.fields import write_solid_fields
    d, comp, fields = rod1_solid
    return d, comp, write_solid_fields(tmp_path_factory.mktemp("fields") / "rod1.vtu", fields)


@pytest.mark.cad
def test_solid_vtu_reads_back_with_its_arrays_and_the_ball_moves_by_C_F(rod1_vtu):
    """pyvista reads the .vtu: quadratic tetrahedra, the twelve point arrays, the parts, units in the field data,
    coordinates in {6}; the displacement interpolated at the ball centre (tool_mm) is the C_F / C_g column of
    its load case (to 1e-5 of the column: the ball is stiff, the FEA's own estimate is ~1e-3)."""
    pv = pytest.importorskip("pyvista")
    d, comp, path = rod1_vtu
    m = pv.read(path)
    assert set(np.unique(m.celltypes)) == {pv.CellType.QUADRATIC_TETRA}
    for key in CASES:
        assert m.point_data[f"displacement_{key}"].shape == (m.n_points, 3)
        assert m.point_data[f"von_mises_{key}"].shape == (m.n_points,)
    assert decode_strings(m.field_data["part_names"]) == ["pipe_holder", "pipe_I", "ring_1", "bend", "ring_2",
                                                          "pipe_II", "ball_holder", "ball"]
    assert set(np.unique(m.cell_data["part"])) == set(range(8))
    assert decode_strings(m.field_data["units"]) == ["mm per N"] * 3 + ["mm per g0"] * 3
    assert decode_strings(m.field_data["stress_units"]) == ["MPa per N"] * 3 + ["MPa per g0"] * 3
    lo, hi = np.asarray(m.bounds).reshape(3, 2).T      # the whole rod (the half mesh mirrored), flange at z = 0
    assert lo[1] == pytest.approx(-hi[1]) and lo[2] == pytest.approx(0.0, abs=1e-9)
    np.testing.assert_allclose(m.field_data["ball_centre_mm"][0], d.tool_mm)
    at_ball = pv.PolyData(np.asarray(d.tool_mm, float)[None, :]).sample(m)
    for k, key in enumerate(CASES):
        col = (comp.C_F if k < 3 else comp.C_g)[:, k % 3]
        np.testing.assert_allclose(at_ball[f"displacement_{key}"][0], col, atol=1e-5 * np.abs(col).max())
        np.testing.assert_allclose(m.field_data["ball_displacement"][k], col, atol=1e-9 * np.abs(col).max())
    # the clamped flange face does not move
    flange = np.abs(np.asarray(m.points)[:, 2]) < 1e-9
    assert flange.sum() > 10 and np.abs(m.point_data["displacement_Fy"][flange]).max() == 0.0


def _p2_at(points, cells, values, x):
    """``values`` (per node) interpolated at ``x`` in the quadratic tetrahedron holding it (VTK node order:
    vertices, then the edges 01, 12, 20, 03, 13, 23), with the barycentric coordinates of its vertices."""
    v = points[cells[:, :4]]                                          # (m, 4, 3)
    Tm = np.transpose(v[:, :3] - v[:, 3:4], (0, 2, 1))              # (m, 3, 3)
    lam3 = np.linalg.solve(Tm, (x - v[:, 3])[:, :, None])[:, :, 0]
    lam = np.column_stack([lam3, 1 - lam3.sum(axis=1)])
    e = int(np.argmax(lam.min(axis=1)))
    assert lam[e].min() > -1e-9, "no element holds the point"
    L = lam[e]
    N = np.concatenate([L * (2 * L - 1), 4 * L[[0, 1, 2, 0, 1, 2]] * L[[1, 2, 0, 3, 3, 3]]])
    return N @ values[cells[e]]


@pytest.mark.cad
def test_solid_vtu_reads_back_with_meshio(rod1_vtu):
    """meshio reads the .vtu (no String arrays): tetra10 cells, the twelve point arrays, the parts and units
    (decoded from their ASCII codes); the displacement at the ball centre, interpolated with the P2 shape
    functions of the element holding it, is the C_F / C_g column of its load case (to 1e-5 of the column)."""
    meshio = pytest.importorskip("meshio")
    d, comp, path = rod1_vtu
    m = meshio.read(path)
    assert [c.type for c in m.cells] == ["tetra10"]
    cells = m.cells[0].data
    for key in CASES:
        assert m.point_data[f"displacement_{key}"].shape == (len(m.points), 3)
        assert m.point_data[f"von_mises_{key}"].shape == (len(m.points),)
    assert decode_strings(m.field_data["part_names"])[:2] == ["pipe_holder", "pipe_I"]
    assert set(np.unique(m.cell_data["part"][0])) == set(range(8))
    assert decode_strings(m.field_data["units"]) == ["mm per N"] * 3 + ["mm per g0"] * 3
    assert decode_strings(m.field_data["stress_units"]) == ["MPa per N"] * 3 + ["MPa per g0"] * 3
    ball = m.field_data["ball_centre_mm"].ravel()
    np.testing.assert_allclose(ball, d.tool_mm)
    for k, key in enumerate(CASES):
        col = (comp.C_F if k < 3 else comp.C_g)[:, k % 3]
        u = _p2_at(m.points, cells, m.point_data[f"displacement_{key}"], ball)
        np.testing.assert_allclose(u, col, atol=1e-5 * np.abs(col).max())
        np.testing.assert_allclose(m.field_data["ball_displacement"].reshape(6, 3)[k], col,
                                   atol=1e-9 * np.abs(col).max())


def _beam_fibre_stress(W, t, y, ro, ri):
    """Von Mises stress of a thin-walled tube's beam theory at the fibres ``y`` (from the centreline, across the
    tangent ``t``), under the section wrenches ``W`` (force, moment) shape=(n, 6): sigma = N / A + (M x y) . t / I,
    tau = T r / J + 2 V . e_theta / A."""
    A, I = np.pi * (ro ** 2 - ri ** 2), np.pi / 4 * (ro ** 4 - ri ** 4)
    F, M = W[..., :3], W[..., 3:]
    r = np.linalg.norm(y, axis=-1)
    e_theta = np.cross(t, y) / r[..., None]
    sigma = np.einsum("...i,...i->...", F, t) / A + np.einsum("...i,...i->...", np.cross(M, y), t) / I
    tau = np.einsum("...i,...i->...", M, t) * r / (2 * I) + 2 * np.einsum("...i,...i->...", F, e_theta) / A
    return np.sqrt(sigma ** 2 + 3 * tau ** 2)


@pytest.mark.cad
def test_frame_stress_agrees_with_the_solid_far_from_the_joints(rod1_solid):
    """Rod 1# (carbon tubes D 40 / d 30 mm): on the tubes' outer surface in the middle of pipe I (80-170 mm from
    the flange) and of pipe II (420-620 mm along the centreline), the solid FEA's nodal von Mises stress equals
    the beam's at that node from the frame's section forces (median within 1.5 %, 80 % of the nodes within
    6 %, at nodes carrying more than half the section's peak; measured: medians 0.995-1.008); and the frame's
    section value (the .vtp's von_mises_<case>) is the beam formula's peak around the circumference."""
    from rodlab.core.chain import centreline_points
    from rodlab.fea.beam_stress import section_von_mises, section_wrenches
    from rodlab.fea.frame import frame_segments
    from rodlab.core.massprops import ball_mass_properties
    d, _, sf = rod1_solid
    segs = frame_segments(d)
    ball, tool = ball_mass_properties(d), np.asarray(d.tool_mm, float)
    ro, ri = 20.0, 15.0
    for lo, hi in ((80.0, 170.0), (420.0, 620.0)):
        s = np.arange(lo, hi, 0.25)
        P, T = centreline_points(segs, s)
        W = section_wrenches(segs, s, tool, ball.mass_kg, ball.com_T_mm + tool)
        X = sf.points_mm
        near = np.argmin(np.linalg.norm(X[:, None, :] - P[None, :, :], axis=2), axis=1)
        y = X - P[near]
        ax = np.einsum("ni,ni->n", y, T[near])
        y -= ax[:, None] * T[near]
        on = (np.abs(ax) < 0.2) & (np.linalg.norm(y, axis=1) > ro - 0.01)   # outer surface, in the span
        assert on.sum() > 200
        for c in range(6):
            beam = _beam_fibre_stress(W[near[on], :, c], T[near[on]], y[on], ro, ri)
            big = beam > 0.5 * beam.max()
            ratio = sf.von_mises[on, c][big] / beam[big]
            assert np.median(ratio) == pytest.approx(1.0, abs=0.015), (lo, c)
            assert np.mean(np.abs(ratio - 1) < 0.06) > 0.8, (lo, c)
        # the frame's section value: the same formula at the fibre where it peaks
        phi = np.linspace(0, 2 * np.pi, 720, endpoint=False)
        e1 = np.cross(T, [0.0, 1.0, 0.0])
        e1 /= np.linalg.norm(e1, axis=1)[:, None]
        e2 = np.cross(T, e1)
        fib = ro * (np.cos(phi)[None, :, None] * e1[:, None, :] + np.sin(phi)[None, :, None] * e2[:, None, :])
        for c in range(6):
            peak = _beam_fibre_stress(W[:, None, :, c], T[:, None, :], fib, ro, ri).max(axis=1)
            np.testing.assert_allclose(section_von_mises(segs, s, W)[:, c], peak, rtol=2e-3)


@pytest.mark.cad
def test_von_mises_of_a_straight_tube_is_beam_theory():
    """A straight steel tube, unit force at the ball: away from the clamp and the ball holder the von Mises
    stress is F / A under the axial load and M r_o / I at the outer fibre under the transverse load."""
    from rodlab.fea.fields import solid_fields
    d = design_from_dict({"format": "rodlab.rod/1", "name": "straight", "L1_mm": 300.0, "L2_mm": 300.0,
                          "gamma_deg": 180.0, "tube": {"material": "steel_304", "outer_diameter_mm": 20.0,
                                                       "wall_mm": 2.0},
                          "rings": {"length_mm": 0.0}, "pipe_holder": {"length_mm": 0.0},
                          "ball_holder": {"length_mm": 0.0}})
    comp, res = _solid(d, None)
    f = solid_fields(d, res)
    ro, ri = 10.0, 8.0
    A, I = np.pi * (ro ** 2 - ri ** 2), np.pi / 4 * (ro ** 4 - ri ** 4)
    x = f.points_mm
    z_ball = d.tool_mm[2]                              # straight up from the flange (z = 0) to the ball
    r = np.hypot(x[:, 0], x[:, 1])
    mid = (x[:, 2] > z_ball / 6) & (x[:, 2] < 5 * z_ball / 6)
    wall = mid & (r > ri - 1e-6)
    np.testing.assert_allclose(f.von_mises[wall, 2], 1.0 / A, rtol=0.01)
    fibres = mid & ((r > ro - 1e-3) | (r < ri + 1e-3)) & (np.abs(x[:, 1]) < 1.0)   # in the bending plane
    assert fibres.sum() > 100
    beam = (z_ball - x[fibres, 2]) * np.abs(x[fibres, 0]) / I
    np.testing.assert_allclose(f.von_mises[fibres, 0], beam, rtol=0.035)


# --- pictures (viz extra; off-screen) -----------------------------------------------------------------------

def _renderer():
    pytest.importorskip("pyvista")
    from rodlab.core.view3d import RenderError, check_offscreen
    try:
        check_offscreen()
    except RenderError as e:
        pytest.skip(str(e))


def _image(path):
    from PIL import Image
    return np.asarray(Image.open(path).convert("RGB"), dtype=float)


def _check_pictures(a, b):
    """Non-blank (a large share of pixels not the white background, many colours) and different."""
    ia, ib = _image(a), _image(b)
    assert ia.shape == ib.shape and ia.shape[0] > 500
    drawn = (ia < 245).any(axis=2).mean()
    assert drawn > 0.03, f"only {100 * drawn:.1f} % of the picture drawn"
    assert len(np.unique(ia.reshape(-1, 3), axis=0)) > 200
    assert np.abs(ia - ib).max(axis=2).__gt__(30).mean() > 0.01     # > 1 % of the pixels changed


def test_rodlab_view_of_the_frame_centreline(tmp_path, capsys):
    """fea --model frame --fields writes the .vtp (displacements and section stress); rodlab view draws it
    off-screen; the pictures of the x and y loads differ, and so do stress and displacement colours."""
    from rodlab.app.cli import main
    vtp = tmp_path / "rod1.vtp"
    assert main(["fea", "rod1", "--model", "frame", "-o", str(tmp_path / "f.json"), "--fields", str(vtp)]) == 0
    assert vtp.stat().st_size > 1000
    _renderer()
    for load in ("x", "gy"):
        assert main(["view", str(vtp), "--load", load, "-o", str(tmp_path / f"{load}.png")]) == 0
    _check_pictures(tmp_path / "x.png", tmp_path / "gy.png")
    # coloured by the sections' stress by default: the displacement colouring is another picture
    assert main(["view", str(vtp), "--load", "x", "--colour", "displacement", "-o", str(tmp_path / "xd.png")]) == 0
    _check_pictures(tmp_path / "x.png", tmp_path / "xd.png")


@pytest.mark.cad
def test_rodlab_view_of_the_solid_fields_changes_with_the_load(rod1_vtu, tmp_path):
    from rodlab.app.cli import main
    _renderer()
    _, _, vtu = rod1_vtu
    for load in ("y", "z"):
        assert main(["view", str(vtu), "--load", load, "-o", str(tmp_path / f"{load}.png")]) == 0
    _check_pictures(tmp_path / "y.png", tmp_path / "z.png")
    assert main(["view", str(vtu), "--load", "gz", "--colour", "displacement", "--scale", "500", "--view", "iso",
                 "-o", str(tmp_path / "gz.png")]) == 0
    _check_pictures(tmp_path / "gz.png", tmp_path / "z.png")


def test_view_and_fields_errors_are_one_line(tmp_path, capsys):
    from rodlab.app.cli import main
    assert main(["fea", "rod1", "--model", "frame", "-o", str(tmp_path / "f.json"), "--fields",
                 str(tmp_path / "f.vtu")]) == 2
    assert "*.vtp" in capsys.readouterr().err
    assert main(["fea", "rod1", "--model", "calc", "-o", str(tmp_path / "c.json"), "--fields",
                 str(tmp_path / "c.vtp")]) == 2
    assert not (tmp_path / "c.json").exists()
    pytest.importorskip("pyvista")
    assert main(["view", str(tmp_path / "none.vtu"), "-o", str(tmp_path / "v.png")]) == 2
    assert "no such file" in capsys.readouterr().err
    (tmp_path / "f.json").write_text("{}")
    bad = tmp_path / "bad.vtu"
    bad.write_text("<VTKFile>")
    assert main(["view", str(bad), "-o", str(tmp_path / "v.png")]) == 2
    err = capsys.readouterr().err
    assert "bad.vtu" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert main(["view", str(bad), "--load", "w", "-o", str(tmp_path / "v.png")]) == 2
    assert "--load 'w': expected one of" in capsys.readouterr().err
    assert not (tmp_path / "v.png").exists()


@pytest.mark.skipif(bool(ctypes.util.find_library("OSMesa")), reason="OSMesa is installed: it would render")
def test_no_opengl_is_a_clear_error_not_a_crash(tmp_path, monkeypatch, capsys):
    """Where VTK can render nowhere (here: forced onto OSMesa, which is absent) it would end the process with a
    segmentation fault; rodlab view says so in one line, exit 2, and writes nothing."""
    pytest.importorskip("pyvista")
    import rodlab.core.view3d as view3d
    from rodlab.app.cli import main
    from rodlab.fea.fields import write_frame_fields
    vtp = write_frame_fields(tmp_path / "rod1.vtp", resolve_design("rod1"))
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSMesaRenderWindow")
    monkeypatch.setattr(view3d, "_offscreen_ok", None)
    monkeypatch.setattr(view3d, "_probe", None)                # not a probe another test started
    assert main(["view", str(vtp), "-o", str(tmp_path / "v.png")]) == 2
    err = capsys.readouterr().err
    assert "3-D rendering is impossible here" in err and "libegl1" in err
    assert not (tmp_path / "v.png").exists()


@pytest.mark.skipif(bool(ctypes.util.find_library("OSMesa")), reason="OSMesa is installed: it would render")
def test_an_offscreen_probe_started_early_gives_the_same_answer(monkeypatch):
    """start_offscreen_check runs the probe in the background; check_offscreen waits for it: where VTK cannot
    render (forced onto the absent OSMesa) the same clear error as the probe run in place, and once known the
    answer is not asked again."""
    pytest.importorskip("pyvista")
    import rodlab.core.view3d as view3d
    monkeypatch.setenv("VTK_DEFAULT_OPENGL_WINDOW", "vtkOSMesaRenderWindow")
    monkeypatch.setattr(view3d, "_offscreen_ok", None)
    monkeypatch.setattr(view3d, "_probe", None)                # not a probe another test started
    view3d.start_offscreen_check()
    assert view3d._probe is not None
    with pytest.raises(view3d.RenderError, match="3-D rendering is impossible here"):
        view3d.check_offscreen()
    assert view3d._probe is None and view3d._offscreen_ok is False
    view3d.start_offscreen_check()                     # known: no second probe
    assert view3d._probe is None


def test_sweep_report_shows_the_base_design_in_3d(tmp_path):
    """rodlab sweep --report: the base design's centreline beside the table, its picture in the page."""
    from rodlab.app.cli import main
    out = tmp_path / "sw.csv"
    assert main(["sweep", "--L1", "200,300", "--L2", "400,500", "--serial", "-o", str(out), "--report"]) == 0
    assert (tmp_path / "sw.base.vtp").stat().st_size > 1000
    html = (tmp_path / "sweep.report.html").read_text()
    pngs = sorted(tmp_path.glob("sw.base.3d_F?.png"))
    try:
        _renderer()
    except pytest.skip.Exception:
        assert not pngs
        return
    assert [p.name for p in pngs] == ["sw.base.3d_Fy.png"]            # rod 1#'s weakest direction: across the bend plane
    assert "sw.base.3d_Fy.png" in html and html.count("data:image/png;base64,") == 2


def test_triangle_sets_render_with_pyvista_too(tmp_path):
    """rodlab.core.render3d's triangle sets (the CAD views) through the same off-screen pyvista renderer: two boxes
    drawn, the views differ; renderer="auto" takes pyvista where it renders."""
    from rodlab.core.render3d import TriangleSet, pick_renderer, render_png
    _renderer()
    box = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float) * [100.0, 20.0, 20.0]
    tri = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1], [2, 3, 7], [2, 7, 6],
                    [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    sets = [TriangleSet("pipe_I", box, tri, (0.2, 0.2, 0.25)),
            TriangleSet("ball", box * 0.3 + [100.0, 0.0, 0.0], tri, (0.9, 0.9, 0.8))]
    a = render_png(sets, tmp_path / "iso.png", "iso", title="boxes", renderer="pyvista")
    b = render_png(sets, tmp_path / "xy.png", "xy", title="boxes", renderer="pyvista")
    _check_pictures(a, b)
    assert pick_renderer("auto") == "pyvista" and pick_renderer("matplotlib") == "matplotlib"


def test_without_pyvista_view_says_what_to_install_and_reports_go_on(tmp_path, monkeypatch, capsys):
    import sys
    import rodlab.core.view3d as view3d
    from rodlab.app.cli import main
    monkeypatch.setitem(sys.modules, "pyvista", None)          # as if the viz extra were not installed
    monkeypatch.setattr(view3d, "_offscreen_ok", None)
    monkeypatch.setattr(view3d, "_probe", None)                # not a probe another test started
    vtp = tmp_path / "rod1.vtp"
    assert main(["fea", "rod1", "--model", "frame", "-o", str(tmp_path / "f.json"), "--fields", str(vtp),
                 "--report"]) == 0
    out = capsys.readouterr().out
    assert "no 3-D views in the report" in out and "rodlab[viz]" in out
    assert vtp.exists() and (tmp_path / "fea.report.html").exists() and not list(tmp_path.glob("*.png"))
    assert main(["view", str(vtp), "-o", str(tmp_path / "v.png")]) == 2
    assert "pip install 'rodlab[viz]'" in capsys.readouterr().err
    from rodlab.core.render3d import pick_renderer
    assert pick_renderer("auto") == "matplotlib"


def test_the_interactive_window_needs_a_display(tmp_path, monkeypatch, capsys):
    pytest.importorskip("pyvista")
    import sys
    from rodlab.app.cli import main
    from rodlab.fea.fields import write_frame_fields
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check is Linux's (DISPLAY / WAYLAND_DISPLAY)")
    vtp = write_frame_fields(tmp_path / "rod1.vtp", resolve_design("rod1"))
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert main(["view", str(vtp)]) == 2
    assert "-o VIEW.png" in capsys.readouterr().err
