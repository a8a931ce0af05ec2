"""One BLAS thread while the demo's other processes run beside it (rodlab.core.blas_threads)."""
from __future__ import annotations

import numpy as np
from threadpoolctl import threadpool_info

from rodlab.core.blas_threads import one_blas_thread


def _blas_threads() -> list[int]:
    return [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]


def test_one_blas_thread_in_the_block_and_the_counts_restored_after():
    np.linalg.svd(np.ones((50, 5)))                     # NumPy's BLAS loaded
    before = _blas_threads()
    assert before                                      # NumPy's OpenBLAS (or MKL) is seen
    with one_blas_thread():
        assert _blas_threads() == [1] * len(before)
        X = np.random.default_rng(0).normal(size=(3280, 42))
        s = np.linalg.svd(X, compute_uv=False)         # the rig diagnosis's shape: same answer on one thread
    assert _blas_threads() == before
    np.testing.assert_allclose(s, np.linalg.svd(X, compute_uv=False), rtol=1e-12)


def test_one_blas_thread_restores_after_an_error():
    before = _blas_threads()
    try:
        with one_blas_thread():
            raise KeyError("a stage failed")
    except KeyError:
        pass
    assert _blas_threads() == before
