"""A quiet local Dask cluster for sweeps and studies.

``LocalCluster`` as Dask starts it prints ~30 ``INFO distributed...`` lines, tries the dashboard's port 8787 (and
warns when another cluster holds it) and suggests ``jupyter-server-proxy``. Here the scheduler and its HTTP
server take free ports, the dashboard runs only when asked (``RODLAB_DASK_DASHBOARD=1``; its address is then
logged), and the cluster's own log lines show only with ``-vv`` (DEBUG), in the workers too.
"""
from __future__ import annotations

import contextlib
import logging
import os
import warnings

__all__ = ["local_cluster", "quiet_dask_logs", "DASHBOARD_ENV", "ONE_THREAD_ENV", "KEEP_MALLOC_DEFAULTS"]

#: environment of a worker process that runs beside others on few cores: one BLAS / OpenMP thread (OpenBLAS, MKL,
#: OpenMP); its small matrices gain nothing from a second thread, which would only spin against the other processes
ONE_THREAD_ENV = {"OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}

#: Dask's configuration that leaves glibc's allocator at its defaults in the workers. Dask sets
#: ``MALLOC_TRIM_THRESHOLD_=65536`` before it spawns a worker (to hand freed memory back to the OS at once); a fixed
#: threshold also fixes glibc's mmap threshold at 128 kB, so every NumPy array above it (a design's (256, 34, 90)
#: stacks are ~6 MB) is mapped and unmapped again, its pages faulted in each time: the study's workers spent ~20 %
#: of their time in the kernel (17.6 s system time of 86 s; 1 s in a serial run). This key of the user's own Dask
#: configuration is overridden for rodlab's local cluster; workers of a remote ``--scheduler`` keep their own
KEEP_MALLOC_DEFAULTS = {"distributed.nanny.pre-spawn-environ.MALLOC_TRIM_THRESHOLD_": None}

log = logging.getLogger(__name__)

#: environment variable that asks for the Dask dashboard (any value but "" and "0")
DASHBOARD_ENV = "RODLAB_DASK_DASHBOARD"


def _verbose() -> bool:
    return log.isEnabledFor(logging.DEBUG)


def quiet_dask_logs() -> None:
    """Dask's loggers in this process at WARNING unless the log is at DEBUG (call after importing Dask)."""
    if _verbose():
        return
    names = [n for n in logging.root.manager.loggerDict if n.split(".")[0] in ("distributed", "tornado", "bokeh")]
    for name in ["distributed", *names]:
        logging.getLogger(name).setLevel(logging.WARNING)


@contextlib.contextmanager
def _environ(values: dict):
    """``os.environ`` with ``values`` while the workers are spawned (they read their log level from it)."""
    old = {k: os.environ.get(k) for k in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for k, v in old.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


def local_cluster(workers: int, env: dict | None = None):
    """A ``LocalCluster`` of ``workers`` single-thread processes (``env``: their environment variables), started
    quietly on free ports; the dashboard only with ``RODLAB_DASK_DASHBOARD=1``; glibc's allocator at its
    defaults in the workers (:data:`KEEP_MALLOC_DEFAULTS`)."""
    import dask
    from dask.distributed import LocalCluster
    quiet_dask_logs()
    dashboard = os.environ.get(DASHBOARD_ENV, "") not in ("", "0")
    level = "info" if _verbose() else "warning"
    with _environ({"DASK_LOGGING__DISTRIBUTED": level}), warnings.catch_warnings(), dask.config.set(KEEP_MALLOC_DEFAULTS):
        if not _verbose():
            warnings.filterwarnings("ignore", message=".*already in use", category=UserWarning)
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0",
                               scheduler_port=0, scheduler_kwargs={"dashboard": dashboard}, env=env or {},
                               silence_logs=logging.DEBUG if _verbose() else logging.WARNING)
    if dashboard:
        log.warning("Dask dashboard: %s", cluster.dashboard_link)
    return cluster
