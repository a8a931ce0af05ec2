"""Heat maps with contours of a sweep (c_rod and mass over L1 x L2), chosen designs marked.

The axes span the swept grid only (half a step beyond its outer designs); a marked design outside the grid is
left out rather than stretching the axes to it.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_figure

__all__ = ["plot_sweep", "PAPER_RODS", "HEAT_CMAP", "grid_extent"]

#: the colour map of every heat map over L1 x L2 (sweeps and studies): dark = low, yellow = high (worse)
HEAT_CMAP = "viridis"

#: the paper's Table 2 geometries (L1, L2) [mm]
PAPER_RODS = {"1#/4#": (300.0, 450.0), "2#/5#": (150.0, 525.0), "3#/6#": (375.0, 600.0)}


def plot_sweep(df, path: str | Path, title: str = "", marks: dict | None = None) -> Path:
    """Two panels: c_rod [um] and mass [g] over L1 x L2; invalid designs grey.

    ``marks``: {label: (L1_mm, L2_mm)} of designs to mark with a star (e.g. the base design, or the paper's
    rods when their family is swept); those outside the grid are not drawn.
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.patheffects as pe
    import matplotlib.pyplot as plt

    L1 = np.unique(df["L1_mm"].to_numpy(float))
    L2 = np.unique(df["L2_mm"].to_numpy(float))
    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    for ax, col, label, scale in ((axes[0], "c_rod_um", "compliance index c_rod [um] (Eq. 23)", 1.0),
                                  (axes[1], "mass_kg", "rod mass [g]", 1e3)):
        Z = np.full((L2.size, L1.size), np.nan)
        for _, r in df.iterrows():
            if r["status"] == "ok":
                Z[np.searchsorted(L2, r["L2_mm"]), np.searchsorted(L1, r["L1_mm"])] = float(r[col]) * scale
        ax.set_facecolor("#dddddd")
        if np.isfinite(Z).any():
            pc = ax.pcolormesh(L1, L2, Z, shading="nearest", cmap=HEAT_CMAP)
            fig.colorbar(pc, ax=ax, label=label)
            if L1.size > 2 and L2.size > 2 and np.isfinite(Z).sum() > 4:
                cs = ax.contour(L1, L2, Z, levels=8, colors="white", linewidths=0.6)
                ax.clabel(cs, fontsize=7, fmt="%.0f")
        xlim, ylim = grid_extent(L1), grid_extent(L2)
        for name, (a, b) in (marks or {}).items():
            if xlim[0] <= a <= xlim[1] and ylim[0] <= b <= ylim[1]:
                ax.plot(a, b, "*", ms=13, color="white", mec="k", zorder=5)
                ax.annotate(name, (a, b), xytext=(6, 6), textcoords="offset points", fontsize=8, color="k",
                            zorder=6, path_effects=[pe.withStroke(linewidth=2.5, foreground="white")])
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_xlabel("L1 [mm] (flange to bend vertex)")
        ax.set_ylabel("L2 [mm] (bend vertex to ball centre)")
        ax.set_title(label, fontsize=10)
    n_bad = int((df["status"] != "ok").sum())
    fig.suptitle(title + (f" — {n_bad} invalid designs shown grey" if n_bad else ""), fontsize=11)
    return atomic_write_figure(path, fig)


def grid_extent(v: np.ndarray) -> tuple[float, float]:
    """The axis limits of a heat map over the sorted grid values ``v`` [mm]: the grid's span plus half a step each
    side (one value: +-5 %)."""
    if v.size == 1:
        return float(v[0]) * 0.95, float(v[0]) * 1.05
    half = float(np.min(np.diff(v))) / 2
    return float(v[0]) - half, float(v[-1]) + half
