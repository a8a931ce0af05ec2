"""One BLAS thread in this process while other processes of the same command run beside it on few cores.

OpenBLAS (NumPy's and SciPy's) starts a thread per core and splits every call above its size threshold between
them, then waits for all of them. When the other cores are busy with the command's own other processes (``rodlab
demo``: its CAD process and its figure process), the thread that is not scheduled holds the call up: the rig
diagnosis's 3280 x 42 SVD (:mod:`rodlab.app.diagnose.rig_outside`) took 0.22-0.48 s in the demo instead of 5-13 ms
(2.6 s of the demo's ~14 s in six calls; measured 2026-11-28, 2 cores). Small matrices gain nothing from a second
thread anyway. MKL (PARDISO's) is limited too; :mod:`rodlab.fea.solver` sets its own count again for a solve.
"""
from __future__ import annotations

from contextlib import contextmanager

from threadpoolctl import threadpool_limits

__all__ = ["one_blas_thread"]


@contextmanager
def one_blas_thread():
    """The block runs with one BLAS thread (OpenBLAS, MKL) in this process; the counts before are restored."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield
