"""One OpenBLAS thread while the demo's other processes run beside it (rodlab.core.blas_threads)."""
from __future__ import annotations


import numpy as np
import pytest
from threadpoolctl import ThreadpoolController, threadpool_info

from rodlab.core.blas_threads import one_blas_thread
from rodlab.core.cores import usable_cores
from rodlab.fea import solver


def _threads(api: str) -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["internal_api"] == api]


@pytest.fixture
def two_threads():
    """OpenBLAS at two threads (whatever the environment set), so that the limit has something to change."""
    np.linalg.svd(np.ones((50, 5)))                     # NumPy's OpenBLAS loaded
    if not _threads("openblas"):
        pytest.skip("NumPy here is not built on OpenBLAS")
    with ThreadpoolController().select(internal_api="openblas").limit(limits=2):
        if max(_threads("openblas")) < 2:
            pytest.skip("OpenBLAS here runs one thread at most")
        yield _threads("openblas")


def test_one_openblas_thread_in_the_block_and_the_counts_restored_after(two_threads):
    with one_blas_thread():
        assert _threads("openblas") == [1] * len(two_threads)
    assert _threads("openblas") == two_threads


def test_the_counts_are_restored_after_an_error(two_threads):
    with pytest.raises(KeyError):
        with one_blas_thread():
            assert _threads("openblas") == [1] * len(two_threads)
            raise KeyError("a stage failed")
    assert _threads("openblas") == two_threads


def test_mkl_is_left_to_the_solver(monkeypatch):
    """PARDISO's MKL keeps its count in the block, and the solver's own setting still takes effect after it, also
    when MKL ran one thread as the block began (threadpoolctl's MKL limit is per thread: restored, it would have
    pinned the solver's thread at that one)."""
    if not solver.backend_available("pardiso"):
        pytest.skip("PARDISO (MKL) is not available here")
    monkeypatch.delenv("MKL_NUM_THREADS", raising=False)    # a test worker's one thread (conftest): the machine's count
    if usable_cores() < 2:
        pytest.skip("one core: the solver's count is 1, which the bug would also leave")
    lib = solver._pardiso_library().libmkl
    solver._mkl_threads(lib)
    wanted = lib.MKL_Get_Max_Threads()                  # what the solver asks for on this machine
    lib.MKL_Set_Num_Threads(1)                          # what gmsh's mesher leaves behind
    with one_blas_thread():
        assert lib.MKL_Get_Max_Threads() == 1
        lib.MKL_Set_Num_Threads(2)
        assert lib.MKL_Get_Max_Threads() == 2           # not limited in the block
        lib.MKL_Set_Num_Threads(1)
    solver._mkl_threads(lib)
    assert lib.MKL_Get_Max_Threads() == wanted
