"""Figures of a study: the Pareto fronts (predicted accuracy vs mass and vs reach) and, for an L1 x L2 grid,
heat maps of the predicted mean error per method."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.fileio import atomic_write_figure

__all__ = ["plot_pareto", "plot_heatmaps", "pareto_mask"]

_COLORS = {"none": "#999999", "calc": "#e69f00", "fea": "#0072b2", "meas": "#009e73"}


def pareto_mask(cost: np.ndarray, error: np.ndarray) -> np.ndarray:
    """True for the points no other point beats in both ``cost`` and ``error`` (lower is better)."""
    cost, error = np.asarray(cost, float), np.asarray(error, float)
    keep = np.ones(cost.size, dtype=bool)
    for i in range(cost.size):
        better = (cost <= cost[i]) & (error <= error[i]) & ((cost < cost[i]) | (error < error[i]))
        keep[i] = not better.any()
    return keep


def _save(fig, path) -> Path:
    return atomic_write_figure(path, fig)


def _pareto_panel(ax, rows, xcol, xlabel, xscale, method, more_is_better=False):
    x = rows[xcol].to_numpy(float) * xscale
    y = rows["mean_mm"].to_numpy(float)
    lo, hi = rows["mean_p05_mm"].to_numpy(float), rows["mean_p95_mm"].to_numpy(float)
    ax.errorbar(x, y, yerr=[y - lo, hi - y], fmt="o", ms=4, color=_COLORS.get(method, "C0"), alpha=0.55,
                elinewidth=0.8, capsize=2, label=f"{method}: mean error, 90 % band")
    front = pareto_mask(-x if more_is_better else x, y)
    order = np.argsort(x[front])
    ax.plot(x[front][order], y[front][order], "-", color="k", lw=1.2, label="Pareto front")
    for xi, yi, name in zip(x[front], y[front], rows["design"].to_numpy()[front]):
        ax.annotate(name, (xi, yi), xytext=(4, -10), textcoords="offset points", fontsize=7)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("predicted validation error, mean [mm]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def plot_pareto(df, path, method: str, title: str = "") -> Path:
    """Two panels: predicted mean error of ``method`` vs rod mass (less is better) and vs reach (flange to ball;
    more is better: fixtures farther out, more varied orientations), with bands and the Pareto fronts."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    rows = df[(df["status"] == "ok") & (df["method"] == method)]
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    if rows.empty:
        for ax in axes:
            ax.text(0.5, 0.5, "no usable design", ha="center", va="center", transform=ax.transAxes)
    else:
        _pareto_panel(axes[0], rows, "mass_kg", "rod mass [g]", 1e3, method)
        _pareto_panel(axes[1], rows, "reach_mm", "reach: flange to ball centre [mm] (more is better)", 1.0, method,
                      more_is_better=True)
    bad = int((df.drop_duplicates("design")["status"] != "ok").sum())
    fig.suptitle(title + (f" — {bad} designs not usable (see study.csv)" if bad else ""), fontsize=11)
    return _save(fig, path)


def plot_heatmaps(df, path, title: str = "") -> Path | None:
    """Predicted mean error over L1 x L2, one panel per method, each on its own colour scale (the designs are
    compared within a method; the methods' levels differ several-fold); None unless the designs form a grid."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    L1, L2 = np.unique(df["L1_mm"].to_numpy(float)), np.unique(df["L2_mm"].to_numpy(float))
    methods = [m for m in ("none", "calc", "fea", "meas") if (df["method"] == m).any()]
    if L1.size < 2 or L2.size < 2 or not methods or df["design"].nunique() != L1.size * L2.size:
        return None
    fig, axes = plt.subplots(1, len(methods), figsize=(4.8 * len(methods), 4.0), constrained_layout=True,
                             squeeze=False)
    for ax, m in zip(axes[0], methods):
        Z = np.full((L2.size, L1.size), np.nan)
        for r in df[df["method"] == m].itertuples():
            Z[np.searchsorted(L2, r.L2_mm), np.searchsorted(L1, r.L1_mm)] = r.mean_mm
        ax.set_facecolor("#dddddd")
        pc = ax.pcolormesh(L1, L2, Z, shading="nearest", cmap="viridis_r")     # own scale: compare designs
        fig.colorbar(pc, ax=ax, label="predicted mean error [mm]")
        ax.set_title(f"{m} compensation", fontsize=10)
        ax.set_xlabel("L1 [mm]")
        ax.set_ylabel("L2 [mm]")
    fig.suptitle(title + " — grey: not usable", fontsize=11)
    return _save(fig, path)
