"""fea/: elasticity tensors, solid model vs Timoshenko and CalculiX, the frame model, the CLI."""
from __future__ import annotations

import json
import pickle

import numpy as np
import pytest

from rodlab.fea.elasticity import local_frames, element_tensors, rotate_tensor, stiffness_tensor_local
from rodlab import calc_compliance, get_material, mass_properties, resolve_design
from rodlab.core.design_io import design_from_dict


def _as6(C):
    idx = [(0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1)]
    return np.array([[C[i, j, k, l] for (k, l) in idx] for (i, j) in idx])


def test_isotropic_tensor_gives_E_and_nu():
    m = get_material("steel_304")
    S = np.linalg.inv(_as6(stiffness_tensor_local(m)))
    assert 1 / S[0, 0] == pytest.approx(193e3, rel=1e-12)
    assert -S[0, 1] / S[0, 0] == pytest.approx(0.29, rel=1e-12)
    R = local_frames(np.array([[0.3, -0.5, 0.81]]))
    np.testing.assert_allclose(rotate_tensor(stiffness_tensor_local(m), R)[0], stiffness_tensor_local(m),
                               atol=1e-8 * 193e3)


def test_transversely_isotropic_tensor_along_any_axis():
    m = get_material("cfrp")
    a = np.array([0.2, 0.7, -0.4])
    a /= np.linalg.norm(a)
    C = element_tensors([m], np.zeros(1, dtype=int), a[None])[0]
    S = np.linalg.inv(_as6(C))
    # uniaxial stress along the fibre axis -> axial strain 1/E1
    sig = np.outer(a, a)
    s6 = np.array([sig[0, 0], sig[1, 1], sig[2, 2], sig[1, 2], sig[0, 2], sig[0, 1]])
    e6 = S @ s6
    eps = np.array([[e6[0], e6[5] / 2, e6[4] / 2], [e6[5] / 2, e6[1], e6[3] / 2], [e6[4] / 2, e6[3] / 2, e6[2]]])
    assert a @ eps @ a == pytest.approx(1 / 125e3, rel=1e-9)
    # shear in a plane containing the axis -> engineering shear strain 1/G12
    b = np.cross(a, [1.0, 0, 0])
    b /= np.linalg.norm(b)
    tau = np.outer(a, b) + np.outer(b, a)
    t6 = np.array([tau[0, 0], tau[1, 1], tau[2, 2], tau[1, 2], tau[0, 2], tau[0, 1]])
    e6 = S @ t6
    eps = np.array([[e6[0], e6[5] / 2, e6[4] / 2], [e6[5] / 2, e6[1], e6[3] / 2], [e6[4] / 2, e6[3] / 2, e6[2]]])
    assert 2 * (a @ eps @ b) == pytest.approx(1 / 4.5e3, rel=1e-9)


def test_frame_model_is_symmetric_and_bend_softens():
    from rodlab.fea import BendFlexibility, frame_compliance
    d = resolve_design("rod1")
    CF, Cg = frame_compliance(d)
    np.testing.assert_allclose(CF, CF.T, atol=1e-15)
    stiff, _ = frame_compliance(d, BendFlexibility(1.0, 1.0))
    soft, _ = frame_compliance(d, BendFlexibility(3.0, 3.0))
    assert soft[2, 2] > stiff[2, 2] and soft[1, 1] > stiff[1, 1]
    assert soft[0, 0] >= stiff[0, 0]


# --- solid model (needs the cad extra for the mesh) ------------------------------------------------
cad = pytest.importorskip
SOLID = pytest.mark.cad


def _mesher():
    pytest.importorskip("build123d")
    pytest.importorskip("gmsh")
    from rodlab.geometry import mesh_rod
    return mesh_rod


def _straight(material):
    return design_from_dict({"format": "rodlab.rod/1", "name": "straight", "L1_mm": 300.0, "L2_mm": 300.0,
                             "gamma_deg": 180.0, "tube": {"material": material, "outer_diameter_mm": 20.0,
                                                          "wall_mm": 2.0},
                             "rings": {"length_mm": 0.0}, "pipe_holder": {"length_mm": 0.0},
                             "ball_holder": {"length_mm": 0.0}})


@SOLID
@pytest.mark.parametrize("material", ["steel_304", "cfrp"])
def test_straight_tube_matches_timoshenko(material):
    """Default mesh order and size: bending + shear and axial tip compliance within 1 % of Timoshenko."""
    from rodlab.fea import solid_compliance
    d = _straight(material)
    comp, res = solid_compliance(d, _mesher(), error_estimate=False)
    CF, _ = calc_compliance(d, shear=True)
    np.testing.assert_allclose(np.diag(comp.C_F), np.diag(CF), rtol=0.01)
    assert np.abs(comp.C_F - np.diag(np.diag(comp.C_F))).max() < 1e-4 * comp.C_F.max()
    assert res.symmetry_defect < 1e-6


@SOLID
def test_solid_rod_mass_symmetry_and_provenance():
    from rodlab.fea import solid_compliance
    d = resolve_design("rod4")
    comp, res = solid_compliance(d, _mesher(), size_mm=6.0, error_estimate=True)
    assert res.mass_kg == pytest.approx(mass_properties(d).mass_kg, rel=1e-4)
    assert res.symmetry_defect < 1e-6
    prov = comp.provenance
    assert prov["dofs"] == res.dofs and prov["mesh"]["order"] == 2
    err = prov["discretisation_error"]
    assert 0 < err["max_relative_C_F"] < 0.02
    # the solid is softer than the Euler-Bernoulli closed form (shear, bend ovalisation), never stiffer
    CF, _ = calc_compliance(d)
    assert np.all(np.diag(comp.C_F) > np.diag(CF))


def test_section_rigid_motion_recovers_a_rigid_motion_and_is_least_squares():
    """The ball's rigid motion: an exact rigid field (any origin offset of the nodes) is recovered to round-off,
    on a half set of nodes too (their images carry the symmetric / antisymmetric fields), and with a non-rigid
    part added the fit is the least-squares one (residual orthogonal to the six rigid fields)."""
    from rodlab.fea.solid import ANTISYMMETRIC_CASES, section_rigid_motion
    rng = np.random.default_rng(4)
    X = rng.normal(size=(300, 3)) * 9.0 + np.array([4.0, 0.0, -30.0])
    t, th = rng.normal(size=(3, 6)), rng.normal(size=(3, 6)) * 1e-2
    U = t[None] + np.cross(th[None], X[:, :, None], axis=1)                        # (n, 3, 6)
    t_fit, th_fit = section_rigid_motion(X, U.reshape(-1, 6), half=False)
    np.testing.assert_allclose(t_fit, t, atol=1e-12 * np.abs(U).max())
    np.testing.assert_allclose(th_fit, th, atol=1e-13)
    noise = rng.normal(size=U.shape) * 1e-3
    t_fit, th_fit = section_rigid_motion(X, (U + noise).reshape(-1, 6), half=False)
    res = (U + noise) - t_fit[None] - np.cross(th_fit[None], X[:, :, None], axis=1)
    rigid = [np.broadcast_to(e, X.shape) for e in np.eye(3)] + [np.cross(e, X) for e in np.eye(3)]
    for f in rigid:
        assert np.abs(np.einsum("nc,nck->k", f, res)).max() < 1e-9 * np.abs(np.einsum("nc,nck->k", f, noise)).max()
    # half: nodes with y >= 0; each case's field is symmetric or antisymmetric about y = 0
    Xh = X * np.array([1.0, 0.0, 1.0]) + np.abs(X) * np.array([0.0, 1.0, 0.0])
    anti = np.isin(np.arange(6), ANTISYMMETRIC_CASES)
    sym_t, sym_th = np.array([1.0, 0.0, 1.0])[:, None], np.array([0.0, 1.0, 0.0])[:, None]   # kept if symmetric
    t_s = t * np.where(anti, 1.0 - sym_t, sym_t)
    th_s = th * np.where(anti, 1.0 - sym_th, sym_th)
    Uh = t_s[None] + np.cross(th_s[None], Xh[:, :, None], axis=1)
    t_fit, th_fit = section_rigid_motion(Xh, Uh.reshape(-1, 6), half=True)
    np.testing.assert_allclose(t_fit, t_s, atol=1e-12 * np.abs(Uh).max())
    np.testing.assert_allclose(th_fit, th_s, atol=1e-13)


@SOLID
def test_half_model_equals_mirrored_whole():
    """The symmetry half-model (two solves, u_y or u_x,u_z held on y_T = 0) reproduces the whole rod meshed as
    the half and its mirror image: C^F, C^g, mass and every nodal displacement of all nine cases (the six and
    the tip moments, M_x and M_z antisymmetric about the plane, M_y symmetric)."""
    from rodlab.fea import mirror_displacements, solve_compliance
    d = resolve_design("rod1")                 # carbon: the mirrored fibre axes must map with the mesh
    pytest.importorskip("gmsh")
    from rodlab.geometry import mesh_rod
    half = mesh_rod(d, size_mm=12.0, half=True)
    assert half.is_half and half.symmetry_facets.size > 0
    assert np.abs(half.mesh.p[1]).min() == 0.0 and half.mesh.p[1].min() > -1e-9
    whole = half.mirrored()
    assert not whole.is_half and whole.mesh.p.shape[1] < 2 * half.mesh.p.shape[1]   # plane nodes shared
    assert half.mirrored() is whole                        # made once: the picture and the field file share it
    again = pickle.loads(pickle.dumps(half))               # the mesh cache keeps the half only
    assert again._whole is None and again.mirrored().sha256 == whole.sha256
    np.testing.assert_array_equal(again.mirrored().mesh.t, whole.mesh.t)
    from rodlab.fea.stiffness_assembly import scalar_basis
    b = scalar_basis(whole.mesh)
    assert (b.mapping.detDF(b.X) > 0).all()                # images re-ordered: no inverted element
    rh = solve_compliance(d, half, keep_displacements=True, tip_moments=True)
    rw = solve_compliance(d, whole, keep_displacements=True, tip_moments=True)
    assert rh.mass_kg == pytest.approx(rw.mass_kg, rel=1e-12)
    scale = np.abs(rw.C_F).max()
    np.testing.assert_allclose(rh.C_F, rw.C_F, atol=1e-7 * scale)
    np.testing.assert_allclose(rh.C_g, rw.C_g, atol=1e-7 * np.abs(rw.C_g).max())
    Uw = mirror_displacements(half, rh.displacements, whole)
    np.testing.assert_allclose(Uw, rw.displacements, atol=1e-7 * np.abs(rw.displacements).max())
    np.testing.assert_allclose(rh.ball_motion, rw.ball_motion, atol=1e-7 * np.abs(rw.ball_motion).max())
    # a load across the plane (F_y) moves the tip sideways; the symmetric cases do not
    assert abs(rh.C_F[1, 1]) > 100 * max(abs(rh.C_F[0, 1]), abs(rh.C_F[2, 1]))
    # Maxwell-Betti for the tip wrench: rotation per unit force = translation per unit moment, transposed
    wrench = rh.ball_motion[:, [0, 1, 2, 6, 7, 8]]
    assert np.abs(wrench - wrench.T).max() < 1e-5 * np.abs(wrench).max()
    assert np.abs(wrench[3:, 3:]).max() > 0 and np.abs(wrench[3:, :3]).max() > 0


@SOLID
@pytest.mark.parametrize("backend", ["pardiso", "cholmod"])
def test_fast_solvers_match_the_superlu_fallback(backend):
    """Every installed fast backend (PARDISO reads the node-ordered upper triangle, CHOLMOD the node-ordered
    lower one) solves the half model to the same C_F and C_g as SciPy's SuperLU on the full K."""
    from rodlab.fea import solve_compliance
    from rodlab.fea.solver import backend_available
    pytest.importorskip("gmsh")
    if not backend_available(backend):
        pytest.skip(f"{backend} is not installed here")
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod5")
    rm = mesh_rod(d, size_mm=12.0, half=True)
    slu = solve_compliance(d, rm, backend="superlu")
    assert slu.backend == "superlu" and slu.symmetry_defect < 1e-6
    fast = solve_compliance(d, rm, backend=backend)
    assert fast.backend == backend
    np.testing.assert_allclose(fast.C_F, slu.C_F, atol=1e-9 * np.abs(slu.C_F).max())
    np.testing.assert_allclose(fast.C_g, slu.C_g, atol=1e-9 * np.abs(slu.C_g).max())


@SOLID
def test_pardiso_node_ordering_keeps_the_fill_low():
    """The node ordering handed to PARDISO (its METIS on the vertex graph) is a permutation and leaves the factor
    no fuller than PARDISO's own METIS on the whole DOF graph (within 10 %); the mesh's own node order, or the
    ordering's inverse (PARDISO's permutation read the other way round), fills it several times more."""
    from rodlab.fea.elasticity import element_tensors
    from rodlab.fea.solver import HeldSystem, PatternSolver, backend_available, node_ordering
    from rodlab.fea.stiffness_assembly import assemble_stiffness, scalar_basis
    pytest.importorskip("gmsh")
    if not backend_available("pardiso"):
        pytest.skip("pardiso is not installed here")
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod5")
    rm = mesh_rod(d, size_mm=12.0, half=True)
    basis = scalar_basis(rm.mesh)
    C = element_tensors([d.material_of(p) for p in rm.parts], rm.part_index, rm.tube_axis)
    nodes = node_ordering(basis, "pardiso")
    assert np.array_equal(np.sort(nodes), np.arange(basis.N))

    def fill(order, method):
        K = assemble_stiffness(basis, C, node_order=order, upper=True)
        return PatternSolver(HeldSystem(K).pattern, "pardiso", ordering_method=method).factor_nonzeros

    own = fill(None, "amd")                                 # PARDISO's METIS on the DOF graph
    ours = fill(nodes, "natural")
    inverse = np.empty_like(nodes)
    inverse[nodes] = np.arange(nodes.size)
    assert 0 < ours <= 1.1 * own
    assert fill(np.arange(basis.N), "natural") > 2 * own
    assert fill(inverse, "natural") > 2 * own


def test_the_default_solver_is_the_fastest_installed_and_can_be_forced(monkeypatch):
    from rodlab.fea.errors import FeaError
    from rodlab.fea.solver import SOLVER_ENV, SolverBackend, available_backend, backend_available
    monkeypatch.delenv(SOLVER_ENV, raising=False)
    first = next(b.value for b in SolverBackend if backend_available(b))
    assert available_backend() == first
    monkeypatch.setenv(SOLVER_ENV, "SuperLU")
    assert available_backend() == "superlu"
    monkeypatch.setenv(SOLVER_ENV, "mumps")
    with pytest.raises(FeaError, match="pardiso, cholmod, superlu"):
        available_backend()


@SOLID
def test_node_ordered_assembly_and_held_system():
    """K assembled in a node ordering equals the permuted K; a held system solves like the sliced one."""
    import scipy.sparse as sp
    from scipy.sparse.linalg import spsolve
    from rodlab.fea.stiffness_assembly import assemble_stiffness, assembly_plan, scalar_basis
    from rodlab.fea.elasticity import element_tensors
    from rodlab.fea.solver import HeldSystem
    pytest.importorskip("gmsh")
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod4")
    rm = mesh_rod(d, size_mm=14.0, half=True)
    basis = scalar_basis(rm.mesh)
    C = element_tensors([d.material_of(p) for p in rm.parts], rm.part_index, rm.tube_axis)
    K = assemble_stiffness(basis, C)
    nodes = np.random.default_rng(1).permutation(basis.N)
    dof = (3 * nodes[:, None] + np.arange(3)).ravel()
    Kp = assemble_stiffness(basis, C, node_order=nodes)
    assert abs(Kp - K[dof][:, dof]).max() < 1e-12 * abs(K).max()
    # upper=True: the blocks on and above the block diagonal only (the lower triangle when read as CSC)
    plan = assembly_plan(basis, nodes, upper=True)
    Ku = assemble_stiffness(basis, C, plan=plan)
    assert plan.upper and np.array_equal(plan.node_order, nodes) and np.all(plan.brow <= plan.bcol)
    P = Kp.tocoo()
    up = P.row // 3 <= P.col // 3
    ref_u = sp.csr_matrix((P.data[up], (P.row[up], P.col[up])), shape=P.shape)
    assert Ku.nnz == ref_u.nnz and Ku.nnz < 0.6 * Kp.nnz
    assert abs(Ku - ref_u).max() < 1e-12 * abs(K).max()
    held = np.zeros(K.shape[0], dtype=bool)
    held[(3 * basis.get_dofs(rm.flange_facets).all()[:, None] + np.arange(3)).ravel()] = True
    held[3 * basis.get_dofs(rm.symmetry_facets).all() + 1] = True
    f = np.random.default_rng(2).normal(size=K.shape[0])
    f[held] = 0.0
    u = spsolve(HeldSystem(K).matrix(held), f)
    free = ~held
    ref = spsolve(sp.csc_matrix(K[free][:, free]), f[free])
    np.testing.assert_allclose(u[free], ref, rtol=1e-7, atol=1e-9 * np.abs(ref).max())
    assert np.all(u[held] == 0.0)


@SOLID
def test_calculix_agrees(tmp_path):
    from rodlab.fea import solve_compliance
    from rodlab.fea.calculix import ccx_available, run_ccx_compliance
    if ccx_available() is None:
        pytest.skip("CalculiX (ccx) is not installed")
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod1")                 # carbon: exercises the per-element orientations
    rm = mesh_rod(d, size_mm=8.0)
    ours = solve_compliance(d, rm).C_F
    theirs = run_ccx_compliance(d, rm, workdir=tmp_path)
    big = np.abs(ours) > 1e-3 * np.abs(ours).max()
    np.testing.assert_allclose(theirs[big], ours[big], rtol=0.005)


@SOLID
def test_cli_fea_models(tmp_path, capsys):
    from rodlab.app.cli import main
    for model in ("frame", "calc"):
        out = tmp_path / f"{model}.json"
        assert main(["fea", "rod2", "--model", model, "-o", str(out)]) == 0
        assert json.loads(out.read_text())["method"] == ("fea" if model == "frame" else "calc")
    out = tmp_path / "solid.json"
    png = tmp_path / "def.png"
    assert main(["fea", "rod5", "-o", str(out), "--size", "6", "--no-error-estimate", "--png", str(png)]) == 0
    data = json.loads(out.read_text())
    assert data["method"] == "fea" and data["provenance"]["model"] == "solid" and png.stat().st_size > 10_000
    assert main(["fea", "rod5", "--model", "frame", "--size", "3", "-o", str(out)]) == 2
    # the whole rod (--no-symmetry) and the half model agree to the discretisation (their meshes differ)
    whole = tmp_path / "whole.json"
    assert main(["fea", "rod5", "-o", str(whole), "--size", "6", "--no-error-estimate", "--no-symmetry"]) == 0
    dw = json.loads(whole.read_text())
    assert dw["provenance"]["symmetry"] == "whole mesh" and "half" in data["provenance"]["symmetry"]
    np.testing.assert_allclose(np.diag(dw["C_F_mm_per_N"]), np.diag(data["C_F_mm_per_N"]), rtol=0.005)
