"""The cores this process may run on: what the sparse solver's MKL and the test runner's workers are counted by."""
from __future__ import annotations

import os

__all__ = ["usable_cores"]


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity: a `taskset` or a container's cpuset counts); where the
    platform has no affinity (macOS, Windows), the machine's count."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1
