"""fea/error_estimate.py: the stress-recovery estimate of the solid FEA's discretisation error.

Physics checked: a field the P2 space holds exactly (uniform strain) has no error, also across a bond between
two materials (the stress jumps there: averaging per part keeps it exact); on a cantilever the Gram matrix is
symmetric positive semi-definite (compliance errors are energies) and adding it moves the coarse compliance to
within a fraction of its error of a much finer solve; the rod's compliance file carries it by default.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse.linalg as spla
from skfem import MeshTet, MeshTet2

from rodlab.core.design_io import resolve_design
from rodlab.core.enums import ErrorEstimate
from rodlab.core.materials import get_material
from rodlab.fea.elasticity import element_tensors
from rodlab.fea.error_estimate import node_basis, recovery_error_matrix
from rodlab.fea.errors import FeaError
from rodlab.fea.stiffness_assembly import assemble_body_force, assemble_stiffness, scalar_basis, scalar_element


def _bar(n: int):
    """A 100 x 10 x 10 mm bar along x, curved-P2 mesh (n elements along x), clamp at x = 0."""
    m = MeshTet.init_tensor(np.linspace(0, 100, n + 1), np.linspace(0, 10, 3), np.linspace(0, 10, 3))
    return MeshTet2.from_mesh(m)


def _setup(mesh, materials):
    part = (mesh.p[0, mesh.t[:4]].mean(axis=0) > 50).astype(int) if len(materials) > 1 else np.zeros(mesh.nelements, int)
    C = element_tensors(materials, part, np.tile([1.0, 0.0, 0.0], (mesh.nelements, 1)))
    basis = scalar_basis(mesh, intorder=4)
    return basis, C, part


def test_a_uniform_strain_has_no_error_even_across_two_materials():
    mesh = _bar(4)
    basis, C, part = _setup(mesh, [get_material("steel_304"), get_material("cfrp")])
    x = basis.doflocs                                               # (3, N)
    grad = np.array([[1e-3, 2e-4, 0.0], [0.0, -3e-4, 1e-4], [5e-4, 0.0, 2e-4]])
    U = np.stack([(grad @ x).T.ravel(), (0.5 * grad.T @ x).T.ravel()], axis=1)   # two affine fields
    E = recovery_error_matrix(node_basis(mesh, scalar_element(mesh)), C, part, U)
    energy = 2e5 * (1e-3) ** 2 * 1e4                               # the fields' energy scale: E_mod eps^2 volume
    assert np.abs(E).max() < 1e-12 * energy
    # averaged across the bond as if one part, the jump of the stress would show as an error
    E_one = recovery_error_matrix(node_basis(mesh, scalar_element(mesh)), C, np.zeros_like(part), U)
    assert E_one[0, 0] > 1e-6 * energy


def _cantilever_compliance(n: int):
    """Compliance under self-weight-like load (1 N spread over the bar, along y: the same problem on every mesh)
    of the steel bar with n elements along it, and the recovery estimate of its error."""
    mesh = _bar(n)
    basis, C, part = _setup(mesh, [get_material("steel_304")])
    K = assemble_stiffness(basis, C).tocsr()
    f = np.zeros((3,) + basis.dx.shape)
    f[1] = 1.0 / 1e4                                                # 1 N over the 100 x 10 x 10 mm
    F = assemble_body_force(basis, f)
    free = np.ones(3 * basis.N, dtype=bool)
    free[(3 * np.nonzero(basis.doflocs[0] < 1e-9)[0][:, None] + np.arange(3)).ravel()] = False
    U = np.zeros(3 * basis.N)
    U[free] = spla.spsolve(K[free][:, free].tocsc(), F[free])
    E = recovery_error_matrix(node_basis(mesh, scalar_element(mesh)), C, part, U[:, None])
    return float(F @ U), float(E[0, 0])


def test_the_estimate_on_a_cantilever_is_an_energy_and_about_the_error():
    c_coarse, e_coarse = _cantilever_compliance(3)
    c_mid, e_mid = _cantilever_compliance(12)
    c_fine, e_fine = _cantilever_compliance(48)
    true = c_fine - c_coarse                                       # a lower bound of the coarse mesh's error
    assert c_coarse < c_mid < c_fine and e_coarse > e_mid > e_fine > 0   # too stiff; less so when refined
    # the clamped face's edges are singular (order ~1.5 here): recovery sees about a third of the error there
    assert 0.2 < e_coarse / true < 1.5, (e_coarse, true)
    assert 0.2 < e_mid / (c_fine - c_mid) < 1.5
    assert abs(c_fine - (c_coarse + e_coarse)) < true              # adding it moves toward the fine solve


@pytest.fixture(scope="module")
def rod1_runs():
    from rodlab.fea.compute import solid_compliance
    from rodlab.geometry import mesh_rod
    d = resolve_design("rod1")
    return {how: solid_compliance(d, mesh_rod, size_mm=22.5, error_estimate=how, keep_displacements=True)
            for how in ErrorEstimate}


def test_the_rods_compliance_file_carries_the_recovery_estimate(rod1_runs):
    comp, res = rod1_runs[ErrorEstimate.RECOVERY]
    E = res.error_matrix
    assert E.shape == (6, 6) and np.allclose(E, E.T)
    assert np.linalg.eigvalsh(E).min() > -1e-9 * np.abs(E).max()   # positive semi-definite
    assert E[0, 1] == 0.0 and E[1, 2] == 0.0                        # symmetric and antisymmetric fields: orthogonal
    err = comp.provenance["discretisation_error"]
    assert err["method"].startswith("stress recovery")
    assert 1e-4 < err["max_relative_C_F"] < 2e-2                  # 0.01-2 % at 1.5 x the default size
    np.testing.assert_allclose(err["C_F_mm_per_N"], np.abs(E[:3, :3]))
    none, _ = rod1_runs[ErrorEstimate.NONE]
    assert "discretisation_error" not in none.provenance
    np.testing.assert_allclose(none.C_F, comp.C_F, rtol=1e-12)      # the estimate does not touch the solve


def test_an_unknown_estimate_is_refused_with_the_choices():
    from rodlab.fea.compute import solid_compliance
    with pytest.raises(FeaError, match="recovery"):
        solid_compliance(resolve_design("rod1"), None, error_estimate="zz")


def test_the_half_mesh_estimate_is_the_whole_rods(rod1_runs):
    """The half mesh's estimate (x 2, symmetric and antisymmetric fields orthogonal) against the estimate on the
    mirrored whole mesh with the mirrored displacements: the same up to the averaging at the plane, which sees one
    side only (a lost factor 2 would be 50 % off)."""
    from rodlab.fea.solid import ANTISYMMETRIC_CASES, mirror_displacements
    d = resolve_design("rod1")
    _, res = rod1_runs[ErrorEstimate.RECOVERY]
    half = res.rod_mesh
    whole = half.mirrored()
    C = element_tensors([d.material_of(p) for p in whole.parts], whole.part_index, whole.tube_axis)
    E = recovery_error_matrix(node_basis(whole.mesh, scalar_element(whole.mesh)), C, whole.part_index,
                              mirror_displacements(half, res.displacements, whole))
    np.testing.assert_allclose(np.diag(res.error_matrix), np.diag(E), rtol=0.1)
    anti = np.isin(np.arange(6), ANTISYMMETRIC_CASES)
    assert np.abs(E[anti[:, None] != anti[None, :]]).max() < 1e-6 * np.abs(E).max()


def test_richardson_is_still_there_and_agrees_in_sign_of_size(rod1_runs):
    """``--error-estimate richardson``: the second solve at 1.5 x the size; the same compliance as the recovery
    run, an estimate of the same order or smaller (it assumes order 3, the rod converges like h)."""
    rich, _ = rod1_runs[ErrorEstimate.RICHARDSON]
    rec, _ = rod1_runs[ErrorEstimate.RECOVERY]
    err = rich.provenance["discretisation_error"]
    assert err["method"].startswith("Richardson, sizes 22.5 and 33.75 mm")
    np.testing.assert_allclose(rich.C_F, rec.C_F, rtol=1e-12)
    assert 0 < err["max_relative_C_F"] < 2 * rec.provenance["discretisation_error"]["max_relative_C_F"]


def test_contradicting_estimate_options_are_refused_before_any_work(tmp_path, capsys):
    from rodlab.app.cli.main import main
    out = tmp_path / "r.json"
    assert main(["fea", "rod1", "--model", "solid", "--no-error-estimate", "--error-estimate", "richardson",
                 "-o", str(out)]) == 2
    assert "contradict" in capsys.readouterr().err and not out.exists()
