"""One OpenBLAS thread in this process while other processes of the same command run beside it on few cores.

OpenBLAS (NumPy's and SciPy's) starts a thread per core and splits every call above its size threshold between
them, then waits for all of them. When the other cores are busy with the command's own other processes (``rodlab
demo``: its CAD process and its figure process), the thread that is not scheduled holds the call up: in a demo
run measured on 2 cores (2026-11-28) four of the rig diagnosis's six 3280 x 42 SVDs
(:mod:`rodlab.app.diagnose.rig_outside`) took 0.22-0.48 s each instead of 5-13 ms, 1.6 s in all; it comes and
goes with the other processes' load. Small matrices gain nothing from a second thread anyway.

Only OpenBLAS is limited. MKL (PARDISO's solver, :mod:`rodlab.fea.solver`) is left alone: threadpoolctl sets MKL's
count per thread, which would override the count the solver sets for a solve, also after the block.
"""
from __future__ import annotations

from contextlib import contextmanager

from threadpoolctl import ThreadpoolController

__all__ = ["one_blas_thread"]


@contextmanager
def one_blas_thread():
    """The block runs with one OpenBLAS thread in this process (every OpenBLAS loaded when it starts: NumPy's and
    SciPy's); the counts before are restored after it, also on an error."""
    with ThreadpoolController().select(internal_api="openblas").limit(limits=1):
        yield
