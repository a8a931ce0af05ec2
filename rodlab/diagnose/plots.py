"""Diagnosis figures: residuals before / after by load and branch, against time, measured vs predicted."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..fileio import atomic_write_figure

__all__ = ["plot_rig_diagnosis", "plot_campaign_diagnosis"]


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
    return [atomic_write_figure(Path(out_dir) / "diagnosis_rig.png", fig, 110)]


def plot_campaign_diagnosis(diag, fits, out_dir, noise_mm: float) -> list[Path]:
    """``diagnosis_campaign.png``: residual length of every point before (the identified model) and after (with
    the found physics), grouped by clamping position, the findings marked; with validation points, the
    validation error distribution of the nominal, identified and corrected models (``error_distributions.png``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    before = np.linalg.norm(fits.before.residuals_mm, axis=1) * 1e3
    after = np.full(before.shape, np.nan)
    if fits.after is not None:
        after[fits.kept] = np.linalg.norm(fits.after.residuals_mm, axis=1) * 1e3
    x = np.arange(before.size)
    fig, ax = plt.subplots(figsize=(13, 4.8), constrained_layout=True)
    _shade_positions(ax, fits, diag)
    ax.plot(x, before, "o", ms=4, color="tab:red", label=f"identified model: rms {diag.rms_before_mm * 1e3:.1f} um")
    if fits.after is not None:
        ax.plot(x, after, "s", ms=4, mfc="none", color="tab:blue",
                label=f"with the found physics: rms {diag.rms_after_mm * 1e3:.1f} um")
        dropped = ~fits.kept
        if dropped.any():
            ax.plot(x[dropped], before[dropped], "x", ms=10, mew=2, color="k", label="dropped as outlier")
    ax.axhline(noise_mm * 1e3 * np.sqrt(3), color="k", lw=0.8, ls=":",
               label=f"expected length from device noise ({noise_mm * 1e3:.1f} um per reading)")
    ax.set_yscale("log")
    from matplotlib.ticker import FuncFormatter
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if str(f"{v:g}")[0] in "25" else ""))
    ax.set_xticks(x)
    ax.set_xticklabels(fits.labels, rotation=90, fontsize=6)
    ax.set_ylabel("residual length per point [um]")
    names = ", ".join(f.effect + (f" at {f.location}" if f.location else "") for f in diag.findings) or "nothing"
    fig.suptitle(f"campaign diagnosis: {diag.verdict}; found {names}", fontsize=10)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    ax.grid(True, lw=0.3, which="both")
    out = [atomic_write_figure(Path(out_dir) / "diagnosis_campaign.png", fig, 110)]
    if fits.validation_errors_mm is not None:
        from rodlab.calibrate.plots import plot_error_distributions
        e = fits.validation_errors_mm
        out.append(plot_error_distributions({"nominal": e["nominal"], "identified": e["before"],
                                             "with the found physics": e["after"]}, out_dir,
                                            "validation errors: the found physics modelled"))
    return out


def _shade_positions(ax, fits, diag) -> None:
    """Alternate grey bands per clamping position; a position a finding names is shaded orange."""
    named = {f.location.split(":")[1] for f in diag.findings if (f.location or "").startswith("position:")}
    for j in np.unique(fits.position):
        m = np.nonzero(fits.position == j)[0]
        colour = "moccasin" if str(j) in named else ("0.92" if j % 2 else "white")
        ax.axvspan(m.min() - 0.5, m.max() + 0.5, color=colour, zorder=0)
        ax.text(m.mean(), 0.98, f"position {j}", transform=ax.get_xaxis_transform(), ha="center", va="top",
                fontsize=8)
