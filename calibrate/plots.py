"""Calibration figures: residuals per clamping position; validation error distributions per method
(the paper's Fig. 10 / 11)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_figure

__all__ = ["plot_residuals", "plot_error_distributions"]


def _save(fig, path) -> Path:
    return atomic_write_figure(path, fig)


def plot_residuals(res, camp, out_dir) -> Path:
    """Residual components [um] of every point, grouped by clamping position."""
    import matplotlib                                                   # heavy (matplotlib: only for plots)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    r = res.residuals_mm * 1e3
    fig, ax = plt.subplots(figsize=(10, 4.2), constrained_layout=True)
    x = np.arange(r.shape[0])
    for c, colour in zip(range(3), ("tab:red", "tab:green", "tab:blue")):
        ax.plot(x, r[:, c], "o-", ms=3, lw=0.6, color=colour, label="xyz"[c] + "_W")
    for j in np.unique(camp.position):
        m = np.nonzero(camp.position == j)[0]
        ax.axvspan(m.min() - 0.5, m.max() + 0.5, color="0.9" if j % 2 else "white", zorder=0)
        ax.text(m.mean(), ax.get_ylim()[1] if False else 0, f"position {j}", ha="center", va="bottom", fontsize=8)
    ax.axhline(3 * res.noise_mm * 1e3, color="k", lw=0.5, ls=":")
    ax.axhline(-3 * res.noise_mm * 1e3, color="k", lw=0.5, ls=":", label="+-3 x fit rms")
    ax.set_xticks(x)
    ax.set_xticklabels(camp.labels(), rotation=90, fontsize=6)
    ax.set_ylabel("residual [um]")
    ax.set_title(f"residuals after identification: rms {res.rms_mm * 1e3:.2f} um per reading", fontsize=10)
    ax.legend(fontsize=8, ncol=4)
    ax.grid(True, lw=0.3)
    return _save(fig, Path(out_dir) / "residuals.png")


#: dash patterns of successive cumulative curves
_DASHES = ("--", "-", (0, (5, 2)), (0, (1, 1.2)), (0, (4, 1.5, 1, 1.5)), (0, (8, 2)))


def plot_error_distributions(errors_mm: dict, out, title: str = "") -> Path:
    """Validation position errors per model (the paper's Fig. 10 / 11): box plots of the calibrated models
    and the cumulative distribution of every model, nominal included (log scale: the nominal model's errors
    are millimetres, the calibrated ones tenths).

    errors_mm : {label: shape=(M,) [mm]}, ``"nominal"`` first if present; out : a folder (the figure is
    ``error_distributions.png``) or a ``*.png`` path.
    """
    import matplotlib                                                   # heavy (matplotlib: only for plots)
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if not errors_mm:
        raise ValueError("errors_mm: expected at least one model's validation errors")
    calibrated = {k: np.asarray(v, float) for k, v in errors_mm.items() if k != "nominal"}
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    colour = {label: f"C{i}" for i, label in enumerate(errors_mm)}
    if calibrated:
        box = axes[0].boxplot(list(calibrated.values()), tick_labels=list(calibrated), showmeans=True,
                              patch_artist=True)
        for patch, label in zip(box["boxes"], calibrated):
            patch.set(facecolor=colour[label], alpha=0.35)
    axes[0].set_ylabel("validation position error [mm]")
    axes[0].set_title("after calibration (box: quartiles, line: median, triangle: mean)", fontsize=10)
    for i, (label, e) in enumerate(errors_mm.items()):
        e = np.sort(np.asarray(e, float))
        # curves that coincide (e.g. Calc and Meas on a stiff rod) stay visible: each later one is thinner and
        # drawn on top of the earlier ones, with its own dash pattern
        axes[1].step(e, np.arange(1, e.size + 1) / e.size, where="post", lw=max(3.2 - 0.55 * i, 0.9),
                     color=colour[label], ls=_DASHES[i % len(_DASHES)], zorder=2 + i,
                     label=f"{label}: mean {e.mean():.3f}, max {e.max():.3f} mm")
    axes[1].set_xscale("log")
    axes[1].set_xlabel("validation position error [mm]")
    axes[1].set_ylabel("fraction of points with a smaller error")
    axes[1].set_ylim(0, 1.02)
    axes[1].legend(fontsize=8, loc="upper left")
    for a in axes:
        a.grid(True, lw=0.3, which="both")
    n = len(next(iter(errors_mm.values())))
    fig.suptitle(title or f"validation errors on {n} points", fontsize=11)
    p = Path(out)
    return _save(fig, p / "error_distributions.png" if p.suffix != ".png" else p)
