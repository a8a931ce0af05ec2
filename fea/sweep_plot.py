"""Heat maps with contours of a sweep (c_rod and mass over L1 x L2), the paper's rods marked."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.fileio import atomic_write_figure

__all__ = ["plot_sweep", "PAPER_RODS"]

#: the paper's Table 2 geometries (L1, L2) [mm]
PAPER_RODS = {"1#/4#": (300.0, 450.0), "2#/5#": (150.0, 525.0), "3#/6#": (375.0, 600.0)}


def plot_sweep(df, path: str | Path, title: str = "") -> Path:
    """Two panels: c_rod [um] and mass [g] over L1 x L2; invalid designs hatched grey."""
    import matplotlib
    matplotlib.use("Agg")
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
            pc = ax.pcolormesh(L1, L2, Z, shading="nearest", cmap="viridis")
            fig.colorbar(pc, ax=ax, label=label)
            if L1.size > 2 and L2.size > 2 and np.isfinite(Z).sum() > 4:
                cs = ax.contour(L1, L2, Z, levels=8, colors="white", linewidths=0.6)
                ax.clabel(cs, fontsize=7, fmt="%.0f")
        for name, (a, b) in PAPER_RODS.items():
            ax.plot(a, b, "r*", ms=11, mec="k")
            ax.annotate(f"paper {name}", (a, b), xytext=(5, 5), textcoords="offset points", fontsize=8, color="r")
        ax.set_xlabel("L1 [mm] (flange to bend vertex)")
        ax.set_ylabel("L2 [mm] (bend vertex to ball centre)")
        ax.set_title(label, fontsize=10)
    n_bad = int((df["status"] != "ok").sum())
    fig.suptitle(title + (f" — {n_bad} invalid designs shown grey" if n_bad else ""), fontsize=11)
    return atomic_write_figure(path, fig)
