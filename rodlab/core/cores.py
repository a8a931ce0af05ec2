"""The cores this process may run on: what the sparse solver's MKL, the test runner's workers and rodlab's own
NumPy threads are counted by."""
from __future__ import annotations

import os
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

__all__ = ["usable_cores", "compute_threads", "in_parts"]

T = TypeVar("T")


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity: a `taskset` or a container's cpuset counts); where the
    platform has no affinity (macOS, Windows), the machine's count."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def compute_threads(most: int = 2) -> int:
    """How many threads rodlab's own NumPy work may split into (at most ``most``): the usable cores, held to
    ``OMP_NUM_THREADS`` where that is set to a positive whole number, as it is in the workers of a Dask sweep or a
    parallel test run (:data:`rodlab.core.cluster.ONE_THREAD_ENV`), which share the cores with one another."""
    n = usable_cores()
    limit = os.environ.get("OMP_NUM_THREADS", "").strip()
    if limit.isdigit() and int(limit) > 0:
        n = min(n, int(limit))
    return max(1, min(n, most))


def in_parts(n: int, work: Callable[[int, int], T], parts: int = 2) -> list[T]:
    """``work(lo, hi)`` over ``parts`` contiguous ranges of ``range(n)``, in this order: in threads on as many cores
    as :func:`compute_threads` gives (NumPy's products and reductions release the GIL), else one after the other.
    The ranges do not depend on the cores, so neither does a result summed from the parts in order."""
    cuts = [round(n * k / parts) for k in range(parts + 1)]
    ranges = [(lo, hi) for lo, hi in zip(cuts[:-1], cuts[1:])]
    threads = compute_threads(parts)
    if threads < 2:
        return [work(lo, hi) for lo, hi in ranges]
    with ThreadPoolExecutor(threads, thread_name_prefix="rodlab-part") as pool:
        return list(pool.map(lambda r: work(*r), ranges))
