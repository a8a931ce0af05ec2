"""Figures rendered to PNG in a second process while the caller goes on.

Inside ``with background_figures():`` every :func:`rodlab.core.fileio.atomic_write_figure` pickles its figure
(~20 ms; building a figure takes ~0.07 s, rendering it 0.3-1.3 s on the 2-core machines measured: text layout,
constrained layout, PNG encoding) and hands it to one worker process, which renders and writes it atomically
as the call itself would have. A reader of a figure waits for it (:func:`wait_for_figure`, used by the HTML
embedding); leaving the block waits for all of them and raises the first failure as a
:class:`~rodlab.core.errors.RodlabError` naming the file. A figure that cannot be pickled (a formatter holding a
lambda) is rendered in the caller's process, as outside the block, and so is every figure after the worker is
lost. ``rodlab demo`` renders its figures so (docs/benchmarks/speed.md). The worker is a spawned process: a
script that calls this (or ``rodlab.app.pipeline.run_demo``) needs the ``if __name__ == "__main__":`` guard.
"""
from __future__ import annotations

import logging
import multiprocessing
import os
import pickle
import signal
from concurrent.futures import BrokenExecutor, Future, ProcessPoolExecutor
from contextlib import contextmanager
from pathlib import Path

from .errors import RodlabError
from .fileio import FIGURE_SINK, atomic_write_figure

__all__ = ["background_figures", "BackgroundFigures", "wait_for_figure", "active_background"]

log = logging.getLogger(__name__)


class BackgroundFigures:
    """One worker process rendering pickled figures; ``pending``: path -> its render (see the module)."""

    def __init__(self) -> None:
        self._pool = ProcessPoolExecutor(max_workers=1, mp_context=multiprocessing.get_context("spawn"),
                                         initializer=_ignore_interrupts)
        self._warm = self._pool.submit(_warm_up)          # the worker's imports overlap the caller's work
        self.pending: dict[str, Future] = {}

    def submit(self, path: str | Path, fig, dpi: int, savefig_kw: dict) -> bool:
        """Hand ``fig`` over (closed here); False when it cannot be pickled or the worker is gone (the caller
        renders it)."""
        self.wait(path)                              # the same file twice: in order, whoever renders the second
        try:
            data = pickle.dumps(fig)
        except (pickle.PicklingError, TypeError, AttributeError) as e:
            log.debug("figure %s rendered here: it cannot be pickled (%s)", path, e)
            return False
        try:
            future = self._pool.submit(_render, str(path), data, dpi, savefig_kw)
        except (BrokenExecutor, RuntimeError) as e:  # the worker died (killed, out of memory): render here
            log.warning("figure %s rendered in this process: the figure worker is gone (%s)", path, e)
            return False
        import matplotlib.pyplot as plt             # heavy: loaded by whoever made the figure already
        plt.close(fig)
        self.pending[_key(path)] = future
        return True

    def wait(self, path: str | Path | None = None) -> None:
        """Wait for ``path``'s figure (None: every figure); a failed render raises :class:`RodlabError`."""
        keys = list(self.pending) if path is None else [k for k in (_key(path),) if k in self.pending]
        for key in keys:
            future = self.pending.pop(key)
            try:
                future.result()
            except RodlabError:
                raise
            except Exception as e:                   # the worker's error (or its loss) names the figure
                raise RodlabError(f"{key}: the figure could not be rendered: {type(e).__name__}: {e}; run the "
                                  "command again (a lost worker: memory?), or report it with the figure's name") from e

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


def _key(path: str | Path) -> str:
    """One spelling of a path (``..`` and ``.`` collapsed) for the pending renders."""
    return os.path.abspath(path)


def _ignore_interrupts() -> None:
    """In the worker: Ctrl-C is the caller's to handle (it shuts the worker down); no traceback from here."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _warm_up() -> None:
    import matplotlib                                # heavy: the worker's matplotlib, before the first figure
    matplotlib.use("Agg")
    import matplotlib.pyplot  # noqa: F401  heavy: pyplot (~0.3-0.5 s)


def _render(path: str, data: bytes, dpi: int, savefig_kw: dict) -> str:
    """In the worker: the figure unpickled, rendered and written as :func:`atomic_write_figure` does."""
    return str(atomic_write_figure(path, pickle.loads(data), dpi, **savefig_kw))
