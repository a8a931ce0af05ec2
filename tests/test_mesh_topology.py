"""The straight mesh handed over before gmsh curves it (geometry.mesh_rod ``on_topology``, MeshCache, MeshPrefetch)
and what the solid model does with it (fea.ahead): the same mesh, the same plan, the same analysis, the same
compliance as without it."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from rodlab.core.design_io import resolve_design
from rodlab.core.fem_mesh import LinearTopology
from rodlab.fea.ahead import plan_pattern, solve_ahead, topology_plan
from rodlab.fea.mesh_request import solid_mesh_request
from rodlab.fea.plan_cache import PlanCache, plan_for
from rodlab.fea.solid import solve_compliance
from rodlab.fea.stiffness_assembly import assemble_stiffness, scalar_basis
from rodlab.fea.elasticity import element_tensors
from rodlab.geometry import mesh_rod
from rodlab.geometry.mesh_cache import MeshCache
from rodlab.geometry.mesh_prefetch import MeshPrefetch


@pytest.fixture(scope="module")
def rod1_meshes():
    """rod 1#'s default solid mesh made in two steps (topology handed over) and in one."""
    d = resolve_design("rod1")
    kw = solid_mesh_request(d).kwargs
    got = []
    two_steps = mesh_rod(d, **kw, on_topology=got.append)
    return d, two_steps, mesh_rod(d, **kw), got


def test_the_straight_tetrahedra_are_the_finished_mesh_s_in_its_numbering(rod1_meshes):
    _, two_steps, one_step, got = rod1_meshes
    assert len(got) == 1 and isinstance(got[0], LinearTopology)
    assert two_steps.sha256 == one_step.sha256                   # the same mesh, node for node
    assert np.array_equal(got[0].t, two_steps.mesh.t) and got[0].n_vertices == two_steps.mesh.nvertices


@pytest.mark.parametrize("name", ["rod3", "rod4"])
def test_other_designs_keep_their_mesh_and_numbering(name):
    d = resolve_design(name)
    kw = solid_mesh_request(d).kwargs
    got = []
    two_steps = mesh_rod(d, **kw, on_topology=got.append)
    assert two_steps.sha256 == mesh_rod(d, **kw).sha256
    assert np.array_equal(got[0].t, two_steps.mesh.t)


def test_an_order_1_mesh_hands_over_nothing():
    got = []
    mesh_rod(resolve_design("rod1"), size_mm=30.0, order=1, half=True, on_topology=got.append)
    assert got == []


def test_linear_topology_checks_its_arrays():
    with pytest.raises(ValueError, match="shape \\(4, n_elements\\)"):
        LinearTopology(np.zeros((3, 5), dtype=np.int64), 10)
    with pytest.raises(ValueError, match="0..9"):
        LinearTopology(np.full((4, 2), 10, dtype=np.int64), 10)


def test_the_plan_from_the_straight_mesh_is_the_finished_mesh_s(rod1_meshes):
    _, mesh, _, got = rod1_meshes
    basis = scalar_basis(mesh.mesh)
    made, ref = topology_plan(got[0]), plan_for(basis)
    assert np.array_equal(made.node_order, ref.node_order)
    for name in ("brow", "bcol", "local", "slot"):
        assert np.array_equal(getattr(made, name), getattr(ref, name)), name


def test_the_cache_takes_a_plan_made_ahead_only_where_it_fits(rod1_meshes, tmp_path):
    _, mesh, _, got = rod1_meshes
    basis = scalar_basis(mesh.mesh)
    made = topology_plan(got[0])
    cache = PlanCache(tmp_path)
    assert cache.plan(basis, mesh.sha256, made=made) is made and cache.ahead == 1
    # another mesh's plan (one element's vertices turned) is not used: made anew, correctly
    t = got[0].t.copy()
    t[[0, 1], 0] = t[[1, 0], 0]
    wrong = topology_plan(LinearTopology(t, got[0].n_vertices))
    fresh = PlanCache(None).plan(basis, mesh.sha256, made=wrong)
    assert fresh is not wrong and np.array_equal(fresh.slot, made.slot)


def test_the_analysis_ahead_is_of_the_assembled_matrix_s_pattern_and_solves_alike(rod1_meshes):
    d, mesh, _, got = rod1_meshes
    ahead = solve_ahead(got[0])
    basis = scalar_basis(mesh.mesh)
    C = element_tensors([d.material_of(p) for p in mesh.parts], mesh.part_index, mesh.tube_axis)
    K = assemble_stiffness(basis, C, plan=ahead.plan)
    P = plan_pattern(ahead.plan)
    assert np.array_equal(K.indptr, P.indptr) and np.array_equal(K.indices, P.indices)
    assert ahead.solver_for(K) is ahead.solver
    K_other = K.copy()
    K_other.indices = K_other.indices.copy()
    K_other.indices[[0, 1]] = K_other.indices[[1, 0]]
    assert ahead.solver_for(K_other) is None
    with_ahead = solve_compliance(d, mesh, ahead=solve_ahead(got[0]))
    without = solve_compliance(d, mesh)
    assert "ahead_beside_mesher" in with_ahead.timings_s and "ahead_beside_mesher" not in without.timings_s
    assert np.allclose(with_ahead.C_F, without.C_F, rtol=1e-12, atol=0)
    assert np.allclose(with_ahead.C_g, without.C_g, rtol=1e-12, atol=0)


class _Mesher:
    """A mesher that hands over a topology (when asked to) and returns a token; ``gate`` holds it after that."""

    def __init__(self, topology: LinearTopology | None = None, fail: Exception | None = None):
        self.topology, self.fail = topology, fail
        self.gate = threading.Event()
        self.calls = []

    def __call__(self, design, on_topology=None, **kw):
        self.calls.append(dict(kw, on_topology=on_topology is not None))
        if on_topology is not None and self.topology is not None:
            on_topology(self.topology)
        self.gate.wait(10)
        if self.fail is not None:
            raise self.fail
        return ("mesh", design.name)


_TOPOLOGY = LinearTopology(np.array([[0], [1], [2], [3]], dtype=np.int64), 4)


def test_prefetch_hands_the_topology_over_before_the_mesh():
    d = resolve_design("rod1")
    inner = _Mesher(_TOPOLOGY)
    pre = MeshPrefetch(inner, d, topology=True, size_mm=12.0, grading=None, half=True)
    assert pre.linear_topology(d, size_mm=12.0, grading=None, half=True) is _TOPOLOGY   # the mesh still held
    assert pre.linear_topology(d, size_mm=18.0, grading=None, half=True) is None       # not what is meshed
    inner.gate.set()
    assert pre(d, size_mm=12.0, grading=None, half=True) == ("mesh", d.name)
    assert inner.calls[0]["on_topology"] is True


def test_prefetch_without_a_topology_gives_none_once_the_mesh_is_done():
    d = resolve_design("rod1")
    for inner, topology in ((_Mesher(None), True), (_Mesher(_TOPOLOGY), False)):
        inner.gate.set()
        pre = MeshPrefetch(inner, d, topology=topology, size_mm=12.0, grading=None, half=True)
        assert pre.linear_topology(d, size_mm=12.0, grading=None, half=True) is None
        assert inner.calls[0]["on_topology"] is topology


def test_prefetch_error_before_the_topology_reaches_the_mesh_call():
    d = resolve_design("rod1")
    inner = _Mesher(None, fail=RuntimeError("gmsh could not mesh the rod"))
    inner.gate.set()
    pre = MeshPrefetch(inner, d, topology=True, size_mm=12.0, grading=None, half=True)
    assert pre.linear_topology(d, size_mm=12.0, grading=None, half=True) is None
    with pytest.raises(RuntimeError, match="could not mesh"):
        pre(d, size_mm=12.0, grading=None, half=True)


def test_the_mesh_cache_keys_without_the_callback_and_forwards_it_only_when_it_meshes(tmp_path):
    d = resolve_design("rod1")
    made = []

    def mesher(design, on_topology=None, **kw):
        if on_topology is not None:
            on_topology(_TOPOLOGY)
        return mesh_rod(design, **kw)

    cache = MeshCache(mesher, tmp_path)
    kw = dict(size_mm=30.0, grading=None, half=True)
    first = cache(d, on_topology=made.append, **kw)
    again = cache(d, on_topology=made.append, **kw)
    assert made == [_TOPOLOGY] and (cache.misses, cache.hits) == (1, 1)
    assert again.sha256 == first.sha256
    assert cache.key(d, **kw) == MeshCache(mesher, tmp_path).key(d, **kw)


def test_the_command_plans_beside_the_mesher_on_a_first_run_only(tmp_path, monkeypatch):
    """``rodlab fea --model solid``: a first run makes its plan and analysis from the straight mesh (the provenance
    says how long), a rerun finds the mesh and its plan in the cache; both write the same compliance."""
    import json

    from rodlab.app.cli import main
    monkeypatch.setenv("RODLAB_CACHE_DIR", str(tmp_path / "cache"))
    runs = []
    for name in ("first", "rerun"):
        out = tmp_path / f"{name}.json"
        assert main(["-q", "fea", "rod1", "--model", "solid", "--size", "24", "--no-error-estimate", "-o", str(out)]) == 0
        runs.append(json.loads(out.read_text()))
    assert runs[0]["provenance"]["timings_s"]["ahead_beside_mesher"] > 0
    assert "ahead_beside_mesher" not in runs[1]["provenance"]["timings_s"]
    assert runs[0]["C_F_mm_per_N"] == runs[1]["C_F_mm_per_N"]


def test_a_failing_hand_over_does_not_fail_the_mesh(caplog):
    import logging

    def broken(topology):
        raise RuntimeError("the caller's optional work broke")

    d = resolve_design("rod1")
    with caplog.at_level(logging.WARNING):
        mesh = mesh_rod(d, size_mm=30.0, half=True, on_topology=broken)
    assert mesh.mesh.nelements > 0 and "was not handed over" in caplog.text


def test_a_topology_that_is_not_the_mesh_s_is_not_used(rod1_meshes):
    """A mesher that hands over another mesh's tetrahedra: the plan is rejected block by block, the solve makes
    its own, the compliance is the same, and the provenance does not claim the work beside the mesher."""
    from rodlab.fea.compute import solid_compliance
    d, mesh, _, got = rod1_meshes
    t = got[0].t.copy()
    t[[0, 1], 0] = t[[1, 0], 0]

    class Handing:
        def linear_topology(self, design, **kw):
            return LinearTopology(t, got[0].n_vertices)

        def __call__(self, design, **kw):
            return mesh

    comp, res = solid_compliance(d, Handing(), error_estimate=False)
    ref = solve_compliance(d, mesh)
    assert "ahead_beside_mesher" not in res.timings_s
    assert np.allclose(res.C_F, ref.C_F, rtol=1e-12, atol=0)


def test_keyed_entities_are_scikit_fems():
    """Edges and facets from integer keys (rodlab.core.skfem_tet): the same arrays, order and inverse as
    scikit-fem's own np.unique(axis=1), on a curved P2 mesh and its straight tetrahedra."""
    from skfem import MeshTet1, MeshTet2

    from rodlab.core.skfem_tet import MeshTet1Keyed, MeshTet2Keyed, keyed_entities
    base = MeshTet1.init_ball().refined(2)
    p2 = MeshTet2.init_ball().refined(1) if hasattr(MeshTet2, "init_ball") else MeshTet2.from_mesh(base)
    for plain, keyed in ((base, MeshTet1Keyed(base.p, base.t)),
                         (p2, MeshTet2Keyed(p2.doflocs, p2.dofs.element_dofs))):
        for attr in ("edges", "t2e", "facets", "t2f", "f2t", "boundary_facets"):
            a, b = getattr(plain, attr), getattr(keyed, attr)
            a, b = (a() if callable(a) else a), (b() if callable(b) else b)
            assert a.dtype == b.dtype and np.array_equal(a, b), attr
    t = base.t.astype(np.int64)
    edges = base.elem.refdom.edges
    unsorted = keyed_entities(t, edges, sort=False)
    want = MeshTet1.build_entities(t, edges, sort=False)
    assert all(np.array_equal(x, y) for x, y in zip(unsorted, want))
