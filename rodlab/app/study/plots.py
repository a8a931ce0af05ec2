"""Figures of a study: the Pareto fronts (predicted accuracy vs mass and vs reach) and, for an L1 x L2 grid,
heat maps of the predicted mean error per method."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_figure
from rodlab.fea.sweep_plot import HEAT_CMAP

__all__ = ["plot_pareto", "plot_heatmaps", "pareto_mask", "pareto_labels", "heat_scale"]

_COLORS = {"none": "#999999", "calc": "#e69f00", "fea": "#0072b2", "meas": "#009e73"}


def pareto_mask(cost: np.ndarray, error: np.ndarray) -> np.ndarray:
    """True for the points no other point beats in both ``cost`` and ``error`` (lower is better)."""
    cost, error = np.asarray(cost, float), np.asarray(error, float)
    keep = np.ones(cost.size, dtype=bool)
    for i in range(cost.size):
        better = (cost <= cost[i]) & (error <= error[i]) & ((cost < cost[i]) | (error < error[i]))
        keep[i] = not better.any()
    return keep


#: with this many designs or fewer every point is labelled, not only the Pareto front's
_LABEL_ALL = 12


_CHAR_PT, _LINE_PT = 4.3, 9.0        # a 7-point label's character width and line height [pt]
_OFFSETS = [(4, -10), (4, 3), (-4, -10), (-4, 3), (4, -19), (4, 12), (-4, -19), (-4, 12), (4, -28), (4, 21)]


def pareto_labels(xy_pt, names, frame=None) -> list[tuple[int, str, tuple[float, float], str]]:
    """Where the point labels go: (index of the point, text, offset [pt], horizontal alignment), with the
    points' display positions ``xy_pt`` [pt]. Designs at the same point share one label; every other label
    takes the first of a few offsets around its point where it covers no label placed before it (and stays
    inside ``frame`` = (x0, y0, x1, y1) [pt], the axes, when given), so two designs at the same reach (another
    tube) both keep their names; a label with no such place is left out (a crowded front: every design is in
    study.csv) rather than drawn over another."""
    xy = np.asarray(xy_pt, float).reshape(-1, 2)
    groups: dict[tuple, list] = {}
    for i, (p, name) in enumerate(zip(xy, names)):
        groups.setdefault((round(p[0], 1), round(p[1], 1)), []).append((i, str(name)))
    placed, out = [], []
    for (px, py), members in sorted(groups.items(), key=lambda g: (-g[0][1], g[0][0])):
        text = ", ".join(name for _, name in members)
        spot = _free_spot(px, py, _CHAR_PT * len(text), placed, frame)
        if spot is None:
            continue
        (dx, dy), box = spot
        placed.append(box)
        out.append((members[0][0], text, (float(dx), float(dy)), "left" if dx > 0 else "right"))
    return out


def _free_spot(px: float, py: float, w: float, placed: list, frame) -> tuple | None:
    """The first offset of :data:`_OFFSETS` whose label box (width ``w`` [pt]) at the point covers no box in
    ``placed`` and lies inside ``frame``: ((dx, dy), box), or None."""
    for dx, dy in _OFFSETS:
        x0 = px + dx if dx > 0 else px + dx - w
        box = (x0, py + dy, x0 + w, py + dy + _LINE_PT)
        if frame is not None and not (frame[0] <= box[0] and box[2] <= frame[2] and frame[1] <= box[1]
                                      and box[3] <= frame[3]):
            continue
        if not any(box[0] < b[2] and b[0] < box[2] and box[1] < b[3] and b[1] < box[3] for b in placed):
            return (dx, dy), box
    return None


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
    names = rows["design"].to_numpy()
    shown = np.ones_like(front) if front.size <= _LABEL_ALL else front
    ax.autoscale_view()
    xy_pt = ax.transData.transform(np.column_stack([x, y])[shown]) * 72.0 / ax.figure.dpi
    frame = ax.get_window_extent().extents * 72.0 / ax.figure.dpi
    px, py = x[shown], y[shown]
    for i, text, offset, ha in pareto_labels(xy_pt, names[shown], frame):
        ax.annotate(text, (px[i], py[i]), xytext=offset, textcoords="offset points", fontsize=7, ha=ha)
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


def heat_scale(df, methods):
    """One colour scale for every method's panel (the sweep's colour map): logarithmic when the methods' levels
    differ more than 4-fold, so each panel's own variation stays visible; None without a finite value."""
    from matplotlib.colors import LogNorm, Normalize
    v = df[df["method"].isin(methods)]["mean_mm"].to_numpy(float)
    v = v[np.isfinite(v) & (v > 0)]
    if not v.size:
        return None
    lo, hi = float(v.min()), float(v.max())
    return LogNorm(lo, hi) if hi > 4 * lo else Normalize(lo, hi)


def plot_heatmaps(df, path, title: str = "") -> Path | None:
    """Predicted mean error over L1 x L2, one panel per method on one colour scale (the sweep's colour map:
    yellow is worse), contours for the variation within a method; None unless the designs form a grid. Where a
    cell holds several designs (``--materials`` on a grid) it shows the best of them, and the title says so."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    L1, L2 = np.unique(df["L1_mm"].to_numpy(float)), np.unique(df["L2_mm"].to_numpy(float))
    methods = [m for m in ("none", "calc", "fea", "meas") if (df["method"] == m).any()]
    per_cell = df.groupby(["L1_mm", "L2_mm"])["design"].nunique()
    if L1.size < 2 or L2.size < 2 or not methods or per_cell.size != L1.size * L2.size:
        return None
    if per_cell.max() > 1:
        title = " — ".join(t for t in (title, f"the best of {per_cell.max()} designs in each cell") if t)
    norm = heat_scale(df, methods)
    fig, axes = plt.subplots(1, len(methods), figsize=(4.4 * len(methods) + 1.0, 4.0), constrained_layout=True,
                             squeeze=False)
    pc = None
    for ax, m in zip(axes[0], methods):
        Z = np.full((L2.size, L1.size), np.nan)
        for r in df[df["method"] == m].itertuples():
            i, j = np.searchsorted(L2, r.L2_mm), np.searchsorted(L1, r.L1_mm)
            Z[i, j] = np.fmin(Z[i, j], r.mean_mm)            # NaN (not usable) only where every design is
        ax.set_facecolor("#dddddd")
        pc = ax.pcolormesh(L1, L2, Z, shading="nearest", cmap=HEAT_CMAP, norm=norm)
        if L1.size > 2 and L2.size > 2 and np.isfinite(Z).sum() > 4 and np.nanmax(Z) > np.nanmin(Z):
            cs = ax.contour(L1, L2, Z, levels=6, colors="white", linewidths=0.6)
            ax.clabel(cs, fontsize=7, fmt="%.3f")
        ax.set_title(f"{m} compensation", fontsize=10)
        ax.set_xlabel("L1 [mm]")
        ax.set_ylabel("L2 [mm]")
    if norm is not None:
        fig.colorbar(pc, ax=list(axes[0]), label="predicted mean error [mm] (one scale for every panel)")
    fig.suptitle(title + " — grey: not usable", fontsize=11)
    return _save(fig, path)
