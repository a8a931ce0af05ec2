"""Figures rendered in a second process (``background_figures``): the same PNG as rendered here, readers wait,
failures name the file, unpicklable figures are rendered here."""
from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402
from matplotlib.ticker import FuncFormatter  # noqa: E402

from rodlab.core.errors import RodlabError  # noqa: E402
from rodlab.core.figures_bg import active_background, background_figures, wait_for_figure  # noqa: E402
from rodlab.core.fileio import atomic_write_figure  # noqa: E402


def _figure(label: str, formatter=None):
    fig, ax = plt.subplots(figsize=(4, 3), constrained_layout=True)
    ax.plot([0, 1, 2], [0, 1, 4], "o-", label=label)
    ax.set_title(f"title {label}")
    ax.legend()
    if formatter is not None:
        ax.xaxis.set_major_formatter(formatter)
    return fig


def test_background_figures_match_the_inline_render_and_readers_wait(tmp_path):
    inline = atomic_write_figure(tmp_path / "inline.png", _figure("a"), 90)
    assert active_background() is None
    with background_figures() as bg:
        out = atomic_write_figure(tmp_path / "bg" / "a.png", _figure("a"), 90)
        atomic_write_figure(tmp_path / "twice.png", _figure("first"), 90)
        atomic_write_figure(tmp_path / "twice.png", _figure("second"), 90)       # the same file: in order
        assert plt.get_fignums() == []                                           # handed over, closed here
        wait_for_figure(out)
        assert out.read_bytes() == inline.read_bytes()
        unpicklable = atomic_write_figure(tmp_path / "lambda.png", _figure("c", FuncFormatter(lambda x, _: f"{x:g}")))
        assert unpicklable.exists() and os.path.abspath(unpicklable) not in bg.pending  # rendered here at once
        atomic_write_figure(tmp_path / "mixed.png", _figure("picklable"), 90)
        atomic_write_figure(tmp_path / "sub" / ".." / "mixed.png", _figure("d", FuncFormatter(lambda x, _: "")), 90)
        mixed = (tmp_path / "mixed.png").read_bytes()                     # the second, rendered here, stays
    assert active_background() is None
    assert (tmp_path / "twice.png").read_bytes() == atomic_write_figure(tmp_path / "second.png",
                                                                       _figure("second"), 90).read_bytes()
    assert (tmp_path / "mixed.png").read_bytes() == mixed


def test_a_failed_render_names_the_file_and_writes_nothing(tmp_path):
    with pytest.raises(RodlabError, match=r"bad\.png: the figure could not be rendered"):
        with background_figures():
            atomic_write_figure(tmp_path / "bad.png", _figure("x"), 90, format="no_such_format")
    assert not (tmp_path / "bad.png").exists()
    assert [p.name for p in tmp_path.iterdir()] == []                  # no temporary file left either
