"""How many threads rodlab's own NumPy work takes, and the parts it is split into."""
from __future__ import annotations

import threading

import numpy as np
import pytest

import rodlab.core.cores as cores
from rodlab.core.cores import compute_threads, in_parts


@pytest.mark.parametrize("value, expected", [("1", 1), ("4", 2), ("", 2), ("abc", 2), ("0", 2), ("-3", 2)])
def test_compute_threads_follows_omp_num_threads_where_it_is_a_positive_number(monkeypatch, value, expected):
    monkeypatch.setattr(cores, "usable_cores", lambda: 8)
    monkeypatch.setenv("OMP_NUM_THREADS", value)
    assert compute_threads(2) == expected


def test_compute_threads_never_exceeds_the_usable_cores(monkeypatch):
    monkeypatch.setattr(cores, "usable_cores", lambda: 1)
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert compute_threads(4) == 1


@pytest.mark.parametrize("threads", [1, 2])
@pytest.mark.parametrize("n, parts", [(0, 2), (1, 2), (7, 2), (10, 3)])
def test_in_parts_covers_the_range_once_in_order_whatever_the_threads(monkeypatch, threads, n, parts):
    monkeypatch.setattr(cores, "compute_threads", lambda most=2: min(threads, most))
    seen = in_parts(n, lambda lo, hi: (lo, hi, threading.current_thread().name), parts)
    assert [lo for lo, _, _ in seen] == sorted(lo for lo, _, _ in seen)
    assert [i for lo, hi, _ in seen for i in range(lo, hi)] == list(range(n))
    assert len(seen) == parts
    names = {name for _, _, name in seen}
    if threads == 1:
        assert names == {threading.current_thread().name}        # one after the other, no thread started
    else:
        assert all(name.startswith("rodlab-part") for name in names)


def test_in_parts_passes_a_part_s_error_on(monkeypatch):
    monkeypatch.setattr(cores, "compute_threads", lambda most=2: 2)

    def work(lo, hi):
        if lo > 0:
            raise ValueError(f"part {lo}:{hi} failed")
        return lo

    with pytest.raises(ValueError, match="part 5:10 failed"):
        in_parts(10, work)


def test_the_stiffness_matrix_does_not_depend_on_the_threads(monkeypatch):
    """The assembly's element parts are the same on one core and on two, and added in one order: the same matrix
    bit for bit (a split by the core count would differ in the last bits)."""
    from skfem import MeshTet, MeshTet2

    from rodlab import get_material
    from rodlab.fea.elasticity import stiffness_tensor_local
    from rodlab.fea.stiffness_assembly import assemble_stiffness, scalar_basis
    mesh = MeshTet2.from_mesh(MeshTet.init_tensor(*(np.linspace(0, 1, 4),) * 3))
    basis = scalar_basis(mesh)
    C = np.ascontiguousarray(np.broadcast_to(stiffness_tensor_local(get_material("cfrp")), (mesh.nelements, 3, 3, 3, 3)))
    out = {}
    for threads in (1, 2):
        monkeypatch.setattr(cores, "compute_threads", lambda most=2, t=threads: min(t, most))
        out[threads] = assemble_stiffness(basis, C, chunk=7)
    assert out[1].nnz == out[2].nnz
    assert np.array_equal(out[1].indices, out[2].indices) and np.array_equal(out[1].data, out[2].data)
