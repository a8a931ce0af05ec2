"""The stiffness assembly against scikit-fem's own linear elasticity, its plans, and the per-user plan cache."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab import get_material
from rodlab.fea.elasticity import stiffness_tensor_local
from rodlab.fea.plan_cache import PlanCache, plan_for
from rodlab.fea.stiffness_assembly import assemble_stiffness, assembly_plan, scalar_basis


def _curved_box():
    """A P2 tetrahedral box 3 x 1 x 1 mm whose mid-edge nodes are moved off the straight edges (curved elements)."""
    from skfem import MeshTet, MeshTet2
    m = MeshTet2.from_mesh(MeshTet.init_tensor(np.linspace(0, 3, 5), np.linspace(0, 1, 3), np.linspace(0, 1, 3)))
    x = m.doflocs.copy()
    mid = np.arange(m.nvertices, x.shape[1])
    x[:, mid] += 0.03 * np.sin(np.array([[2.0], [3.0], [5.0]]) * x[[1, 2, 0]][:, mid])
    return MeshTet2(x, m.t)


def _uniform(mesh, material) -> np.ndarray:
    """The material's stiffness tensor [N/mm^2] in every element, its axis along x, shape=(ne, 3, 3, 3, 3)."""
    return np.ascontiguousarray(np.broadcast_to(stiffness_tensor_local(material), (mesh.nelements, 3, 3, 3, 3)))


def test_assembly_equals_scikit_fem_linear_elasticity_on_curved_elements():
    """An isotropic material: K is scikit-fem's ``linear_elasticity`` form assembled on the vector P2 basis (DOFs
    ``3 node + component`` in both), entry for entry, on curved elements."""
    from skfem import Basis, ElementTetP2, ElementVector, asm
    from skfem.models.elasticity import lame_parameters, linear_elasticity
    mesh = _curved_box()
    steel = get_material("steel_304")
    E, nu = 1e3 * steel.E_GPa, steel.nu                    # [N/mm^2]
    basis = scalar_basis(mesh)
    K = assemble_stiffness(basis, _uniform(mesh, steel))
    ref = asm(linear_elasticity(*lame_parameters(E, nu)), Basis(mesh, ElementVector(ElementTetP2()), intorder=3))
    assert K.shape == ref.shape
    assert abs(K - ref).max() < 1e-10 * abs(ref).max()


def test_a_plan_stores_one_triangle_in_the_new_numbering():
    mesh = _curved_box()
    basis = scalar_basis(mesh)
    C = _uniform(mesh, get_material("cfrp"))              # transversely isotropic along x
    order = np.random.default_rng(3).permutation(basis.N)
    full = assemble_stiffness(basis, C)
    plan = assembly_plan(basis, order, upper=True)
    assert np.all(plan.brow <= plan.bcol) and np.all(np.diff(plan.brow) >= 0)
    Ku = assemble_stiffness(basis, C, plan=plan).tocoo()
    dof = (3 * order[:, None] + np.arange(3)).ravel()
    P = full[dof][:, dof].tocoo()
    up = P.row // 3 <= P.col // 3
    assert Ku.nnz == int(up.sum())
    np.testing.assert_allclose(Ku.toarray(), np.where(np.arange(P.shape[0])[:, None] // 3 <= np.arange(P.shape[0]) // 3,
                                                      P.toarray(), 0.0), atol=1e-12 * abs(full).max())
    with pytest.raises(ValueError, match="assembly_plan"):
        assemble_stiffness(scalar_basis(_curved_box().refined()), C, plan=plan)


def test_the_plan_cache_reads_what_it_wrote_and_remakes_a_damaged_entry(tmp_path, caplog):
    mesh = _curved_box()
    basis = scalar_basis(mesh)
    cache = PlanCache(tmp_path)
    made = cache.plan(basis, "mesh-sha", "superlu")
    reader = PlanCache(tmp_path)
    again = reader.plan(basis, "mesh-sha", "superlu")
    assert cache.misses == 1 and reader.hits == 1 and reader.misses == 0 and len(list(tmp_path.glob("*.npz"))) == 1
    for name in ("brow", "bcol", "local", "slot"):
        assert np.array_equal(getattr(made, name), getattr(again, name))
    assert again.node_order is None and not again.upper              # SuperLU: the whole matrix as numbered
    fresh = plan_for(basis, "superlu")
    assert np.array_equal(fresh.slot, again.slot)
    # another mesh (hash) or backend is another entry
    PlanCache(tmp_path).plan(basis, "other-sha", "superlu")
    assert len(list(tmp_path.glob("*.npz"))) == 2
    # a damaged entry (arrays that load but point out of range) is made again and replaced
    entry = tmp_path / f"{cache.key(basis, 'mesh-sha', 'superlu')}.npz"
    with np.load(entry) as z:
        arrays = dict(z)
    arrays["slot"] = arrays["slot"] + 10 ** 6
    np.savez(entry, **arrays)
    c2 = PlanCache(tmp_path)
    p2 = c2.plan(basis, "mesh-sha", "superlu")
    assert c2.misses == 1 and c2.hits == 0 and np.array_equal(p2.slot, fresh.slot)
    assert "does not fit" in caplog.text
    entry.write_bytes(b"not an npz")
    c3 = PlanCache(tmp_path)
    assert np.array_equal(c3.plan(basis, "mesh-sha", "superlu").slot, fresh.slot) and c3.misses == 1
    c4 = PlanCache(tmp_path)
    c4.plan(basis, "mesh-sha", "superlu")
    assert c4.hits == 1                                                 # the replaced entry serves again
    # off: nothing is written
    off = PlanCache(None)
    off.plan(basis, "third-sha", "superlu")
    assert off.hits == off.misses == 0 and len(list(tmp_path.glob("*.npz"))) == 2


def test_the_plan_cache_folder_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("RODLAB_CACHE_DIR", str(tmp_path))
    assert PlanCache().folder == tmp_path / "plans"
    monkeypatch.setenv("RODLAB_CACHE_DIR", "off")
    assert PlanCache().folder is None


def test_an_ordered_triangular_plan_round_trips_and_a_wrong_one_is_refused(tmp_path, monkeypatch):
    """The plan PARDISO gets (node ordering, upper block triangle, 55 blocks per element) comes back from the cache
    and assembles the same K; a plan of the right shapes and ranges whose slots were swapped, or another user's
    file, is not used."""
    from rodlab.fea import plan_cache
    mesh = _curved_box()
    basis = scalar_basis(mesh)
    C = _uniform(mesh, get_material("cfrp"))
    order = np.random.default_rng(5).permutation(basis.N)
    monkeypatch.setattr(plan_cache, "node_ordering", lambda b, backend: order)
    made = PlanCache(tmp_path).plan(basis, "sha", "pardiso")
    assert made.upper and made.local.shape[1] == 55 and np.array_equal(made.node_order, order)
    reader = PlanCache(tmp_path)
    again = reader.plan(basis, "sha", "pardiso")
    assert reader.hits == 1
    K1, K2 = assemble_stiffness(basis, C, plan=made), assemble_stiffness(basis, C, plan=again)
    assert (K1 != K2).nnz == 0
    entry = next(tmp_path.glob("*.npz"))
    with np.load(entry) as z:
        arrays = dict(z)
    arrays["slot"] = arrays["slot"].copy()
    arrays["slot"][0, [0, 1]] = arrays["slot"][0, [1, 0]]               # in range, but the wrong blocks
    np.savez(entry, **arrays)
    swapped = PlanCache(tmp_path)
    assert np.array_equal(swapped.plan(basis, "sha", "pardiso").slot, made.slot) and swapped.misses == 1
    import os
    monkeypatch.setattr(os, "getuid", lambda: entry.stat().st_uid + 1)
    foreign = PlanCache(tmp_path)
    foreign.plan(basis, "sha", "pardiso")
    assert foreign.hits == 0 and foreign.misses == 1
    with pytest.raises(ValueError, match="not both"):
        assemble_stiffness(basis, C, plan=made, upper=True)


def test_the_row_major_order_of_node_pairs_is_the_same_by_radix_and_by_keys():
    from rodlab.fea.stiffness_assembly import _row_major_order
    rng = np.random.default_rng(5)
    rows, cols = rng.integers(0, 3000, 20000), rng.integers(0, 3000, 20000)
    want = np.lexsort((cols, rows))                       # stable: ties keep their order, as both branches do
    np.testing.assert_array_equal(_row_major_order(rows, cols, 3000), want)          # 16-bit radix passes
    np.testing.assert_array_equal(_row_major_order(rows, cols, 70000), want)         # one sort of the keys
