"""The paper's Fig. 8 for a recording: load-deflection per load axis, measured vs fitted vs simulated."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.enums import Phase
from rodlab.core.fileio import atomic_write_figure
from rodlab.core.units import G0

__all__ = ["plot_fit", "format_pm", "format_zero"]

_AX = "xyz"


def format_pm(value: float, se: float, unit: str) -> str:
    """``219.80 +- 0.0031 um/N``: the standard error to two significant digits, the value to the same place."""
    if not (np.isfinite(value) and np.isfinite(se)) or se <= 0:
        return f"{value:.4g} {unit}"
    digits = max(int(-np.floor(np.log10(se))) + 1, 0)
    return f"{value:.{digits}f} +- {se:.{digits}f} {unit}"


def format_zero(z_kg: float) -> str:
    """A zero-load crossing in grams, two significant digits (``-0.042 g``, ``-6.0 g``, ``+12 g``); ``n/a`` when
    undefined (a branch not recorded, or a cross term with no slope)."""
    if not np.isfinite(z_kg):
        return "n/a"
    g = z_kg * 1e3
    if g == 0.0:
        return "0 g"
    return f"{g:+.{max(1 - int(np.floor(np.log10(abs(g)))), 0)}f} g"


def plot_fit(fit, path: str | Path, sim=None, title: str = "") -> Path:
    """One panel per load axis: the displacement along the load axis [um] vs load [kg]; hold means with the
    scatter over repeats (mean +- SD), the fitted loading / unloading lines, the simulated line."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    diag = [ln for ln in fit.lines if ln.component == ln.axis.index]
    n = max(len(diag), 1)
    fig, axes = plt.subplots(2, n, figsize=(5.2 * n, 7.0), squeeze=False, constrained_layout=True,
                             gridspec_kw={"height_ratios": [2.2, 1]})
    h = fit.holds
    xk = h.load_N() / G0               # load in kg: the load cell's force / g0 when measured, else the mass
    xlabel = "measured load / g0 [kg] (load cell)" if h.has_force else "load mass [kg] (hanger included)"
    for ax, rax, ln in zip(axes[0], axes[1], diag):
        ref = sim.C_F[ln.component, ln.axis.index] if sim is not None else ln.slope_mm_per_N
        sel0 = np.array([a is ln.axis for a in h.axis])
        for phase, colour, marker in ((Phase.LOAD, "tab:blue", "o"), (Phase.UNLOAD, "tab:orange", "s")):
            m = sel0 & np.array([p is phase for p in h.phase])
            if m.any():
                r = 1e3 * (h.mean_mm[m, ln.component] - ref * xk[m] * G0 * ln.axis.sign)
                rax.plot(xk[m] + (0.01 if phase is Phase.UNLOAD else -0.01), r, marker, color=colour, ms=3,
                         alpha=0.7, label=str(phase))
        rax.axhline(0, color="k", lw=0.8, ls="--")
        rax.set_xlabel(xlabel)
        rax.set_ylabel("measured - " + ("simulated" if sim is not None else "fit") + " [um]")
        rax.grid(True, lw=0.3)
        rax.legend(fontsize=7)
        sel = np.array([a is ln.axis for a in h.axis])
        for phase, colour, marker in ((Phase.LOAD, "tab:blue", "o"), (Phase.UNLOAD, "tab:orange", "s")):
            m = sel & np.array([p is phase for p in h.phase])
            if not m.any():
                continue
            masses = np.unique(h.mass_kg[m])
            y = [h.mean_mm[m & (h.mass_kg == mk), ln.component] * 1e3 for mk in masses]
            at = [xk[m & (h.mass_kg == mk)].mean() for mk in masses]
            ax.errorbar(at, [v.mean() for v in y], yerr=[v.std(ddof=1) if v.size > 1 else 0 for v in y],
                        fmt=marker, color=colour, ms=5, capsize=3, label=f"measured, {phase} (mean +- SD of repeats)")
            mm = np.linspace(0, h.mass_kg[sel].max(), 50)
            a = ln.intercept_mm[str(phase)]
            ax.plot(mm, 1e3 * (a + ln.slope_mm_per_N * mm * G0 * ln.axis.sign), "-", color=colour, lw=1,
                    label=f"fit, {phase}: zero load at {format_zero(ln.zero_load_kg[str(phase)])}")
        if sim is not None:
            mm = np.linspace(0, h.mass_kg[sel].max(), 50)
            ax.plot(mm, 1e3 * sim.C_F[ln.component, ln.axis.index] * mm * G0 * ln.axis.sign, "k--", lw=1,
                    label=f"simulated ({sim.method})")
        c = f"c{ln.component + 1}{ln.axis.index + 1}"
        ax.set_title(f"load along {ln.axis.value}_T: {c} = "
                     f"{format_pm(ln.slope_mm_per_N * 1e3, ln.se_mm_per_N * 1e3, 'um/N')}", fontsize=10)
        ax.set_xlabel(xlabel)
        ax.set_ylabel(f"ball displacement along {_AX[ln.component]}_T [um]")
        ax.grid(True, lw=0.3)
        ax.legend(fontsize=7)
    if fit.r_rod is not None:
        title = f"{title}  r_rod = {fit.r_rod:.4f} (Eq. 21)".strip()
    fig.suptitle(title, fontsize=11)
    return atomic_write_figure(path, fig)
