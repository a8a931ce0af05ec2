"""Figures rendered to PNG in a second process while the caller goes on.

Inside ``with background_figures():`` every :func:`rodlab.core.fileio.atomic_write_figure` pickles its figure
(~20 ms; building a figure takes ~0.07 s, rendering it 0.3-1.3 s on the 2-core machines measured: text layout,
constrained layout, PNG encoding) and hands it to one worker process, which renders and writes it atomically
as the call itself would have. A reader of a figure waits for it (:func:`wait_for_figure`, used by the HTML
embedding); leaving the block waits for all of them and raises the first failure as a
:class:`~rodlab.core.errors.RodlabError` naming the file. A figure that cannot be pickled (a formatter holding a
lambda) is rendered in the caller's process, as outside the block. ``rodlab demo`` renders its figures so
(docs/benchmarks/speed.md).
"""
from __future__ import annotations

import logging
import multiprocessing
import pickle
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from .errors import RodlabError
from .fileio import FIGURE_SINK, atomic_write_figure

__all__ = ["background_figures", "BackgroundFigures", "wait_for_figure", "active_background"]

log = logging.getLogger(__name__)

class BackgroundFigures:
    """One worker process rendering pickled figures; ``pending``: path -> its render (see the module)."""

    def __init__(self) -> None:
        self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"))
        self._warm = self._pool.submit(_warm_up)          # the worker's imports overlap the caller's work
        self.pending: dict[Path, Future] = {}

    def submit(self, path: str | Path, fig, dpi: int, savefig_kw: dict) -> bool:
        """Hand ``fig`` over (closed here); False when it cannot be pickled (the caller renders it)."""
        try:
            data = pickle.dumps(fig)
        except (pickle.PicklingError, TypeError, AttributeError) as e:
            log.debug("figure %s rendered here: it cannot be pickled (%s)", path, e)
            return False
        import matplotlib.pyplot as plt             # heavy: loaded by whoever made the figure already
        plt.close(fig)
        key = Path(path).absolute()
        self.wait(key)                               # the same file twice: in order
        self.pending[key] = self._pool.submit(_render, str(path), data, dpi, savefig_kw)
        return True

    def wait(self, path: str | Path | None = None) -> None:
        """Wait for ``path``'s figure (None: every figure); a failed render raises :class:`RodlabError`."""
        keys = list(self.pending) if path is None else [k for k in (Path(path).absolute(),) if k in self.pending]
        for key in keys:
            future = self.pending.pop(key)
            try:
                future.result()
            except RodlabError:
                raise
            except Exception as e:                   # the worker's error (or its loss) names the figure
                raise RodlabError(f"{key}: the figure could not be rendered: {type(e).__name__}: {e}") from e

    def shutdown(self) -> None:
        """Stop the worker; renders not yet started are dropped (after a failure or an interrupt)."""
        self._pool.shutdown(wait=True, cancel_futures=True)


@contextmanager
def background_figures():
    """Render the block's figures in a second process; every one written (or the first failure raised) when
    the block ends."""
    bg = BackgroundFigures()
    token = FIGURE_SINK.set(bg)
    try:
        yield bg
        bg.wait()
    finally:
        FIGURE_SINK.reset(token)
        bg.shutdown()


def active_background() -> BackgroundFigures | None:
    """The :class:`BackgroundFigures` of the enclosing :func:`background_figures` block, or None."""
    bg = FIGURE_SINK.get()
    return bg if isinstance(bg, BackgroundFigures) else None


def wait_for_figure(path: str | Path) -> None:
    """Wait until ``path`` is written if a background render of it is pending (else return at once)."""
    bg = active_background()
    if bg is not None:
        bg.wait(path)


def _warm_up() -> None:
    import matplotlib                                # heavy: the worker's matplotlib, before the first figure
    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401  heavy: pyplot (~0.3-0.5 s)


def _render(path: str, data: bytes, dpi: int, savefig_kw: dict) -> str:
    """In the worker: the figure unpickled, rendered and written as :func:`atomic_write_figure` does."""
    return str(atomic_write_figure(path, pickle.loads(data), dpi, **savefig_kw))
