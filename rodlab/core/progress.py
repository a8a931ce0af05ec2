"""Progress bars for long steps, one choice for the whole of rodlab: tqdm, on stderr.

The library never prints: bars are off until the application turns them on (:func:`configure`, which the CLI
calls with ``enabled = stderr is a terminal and not --quiet``). Library code marks its long steps with
:func:`progress` (an iterable or a counter) or :func:`stages` (named steps of one computation); both cost
nothing when bars are off.
"""
from __future__ import annotations

import contextlib
import sys
from collections.abc import Iterable, Iterator

__all__ = ["configure", "progress", "stages", "Stages"]

_ENABLED = False


def configure(enabled: bool) -> None:
    """Turn progress bars on or off for this process."""
    global _ENABLED
    _ENABLED = bool(enabled)


class _Silent:
    """The no-op bar used while bars are off (same methods as the part of tqdm rodlab uses)."""

    def __init__(self, iterable=None, total=None, **_):
        self._it = iterable
        self.n = 0
        self.total = total

    def __iter__(self):
        return iter(self._it if self._it is not None else ())

    def update(self, n=1):
        self.n += n

    def set_postfix_str(self, s="", refresh=True):
        pass

    def close(self):
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def progress(iterable: Iterable | None = None, *, total: int | None = None, desc: str = "", unit: str = "it"):
    """A tqdm bar over ``iterable`` (or a counter of ``total`` to :meth:`update`), or a silent stand-in."""
    if not _ENABLED:
        return _Silent(iterable, total=total)
    from tqdm import tqdm
    return tqdm(iterable, total=total, desc=desc, unit=unit, file=sys.stderr, leave=False, dynamic_ncols=True,
                mininterval=0.2)


class Stages:
    """Named steps of one computation on one bar: ``with s.step("factorise"): ...``."""

    def __init__(self, bar):
        self._bar = bar

    @contextlib.contextmanager
    def step(self, name: str) -> Iterator[None]:
        self._bar.set_postfix_str(name)
        try:
            yield
        finally:
            self._bar.update(1)


@contextlib.contextmanager
def stages(desc: str, names: list[str]) -> Iterator[Stages]:
    """A bar of ``len(names)`` named steps (``desc`` on the left, the current step on the right)."""
    with progress(total=len(names), desc=desc, unit="step") as bar:
        yield Stages(bar)
