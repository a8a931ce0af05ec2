"""Diagnosis figures: residuals before / after by load and branch, against time, measured vs predicted."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from ..fileio import atomic_write_bytes

__all__ = ["plot_rig_diagnosis"]


def plot_rig_diagnosis(model: dict, out_dir, title: str = "") -> list[Path]:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = model["data"]
    before, after = model["base_resid"] * 1e3, model["resid"] * 1e3
    fig, axes = plt.subplots(2, 2, figsize=(12, 7.5), constrained_layout=True)
    for ax, r, lab in ((axes[0, 0], before, "before (simulated model)"), (axes[0, 1], after, "after (found physics)")):
        for unload, colour, name in ((False, "tab:blue", "load"), (True, "tab:orange", "unload")):
            m = (d.unload == unload) & ~d.reference
            ax.plot(np.abs(d.F[m]) / 9.80665 + (0.01 if unload else -0.01), r[m], ".", ms=2, alpha=0.4, color=colour,
                    label=name)
        ax.axhline(0, color="k", lw=0.8)
        ax.set_xlabel("load mass [kg]")
        ax.set_ylabel("residual [um]")
        ax.set_title(f"residuals vs load, {lab}", fontsize=10)
        ax.legend(fontsize=8)
        ax.grid(True, lw=0.3)
    ax = axes[1, 0]
    ax.plot(d.t_abs, before, ".", ms=1.5, alpha=0.4, label="before")
    ax.plot(d.t_abs, after, ".", ms=1.5, alpha=0.4, label="after")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("residual [um]")
    ax.set_title("residuals vs time", fontsize=10)
    ax.legend(fontsize=8, markerscale=5)
    ax.grid(True, lw=0.3)
    ax = axes[1, 1]
    pred = d.y - model["resid"]
    ax.plot(pred * 1e3, d.y * 1e3, ".", ms=2, alpha=0.4)
    lim = [min(pred.min(), d.y.min()) * 1e3, max(pred.max(), d.y.max()) * 1e3]
    ax.plot(lim, lim, "k--", lw=0.8)
    ax.set_xlabel("predicted (with found physics) [um]")
    ax.set_ylabel("measured [um]")
    ax.set_title("measured vs predicted", fontsize=10)
    ax.grid(True, lw=0.3)
    fig.suptitle(title, fontsize=11)
    buf = io.BytesIO()
    fig.savefig(buf, dpi=110)
    plt.close(fig)
    return [atomic_write_bytes(Path(out_dir) / "diagnosis_rig.png", buf.getvalue())]
