"""Diagnosis figures: residuals before / after by load and branch, against time, measured vs predicted."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.calibrate.plots import plot_error_distributions
from ...core.fileio import atomic_write_figure
from .wording import explained_share

__all__ = ["plot_rig_diagnosis", "plot_campaign_diagnosis"]


def _finding_names(diag) -> str:
    """``friction (100 %), tare at x (3 %)``: each finding with the share of the residual it explains."""
    return ", ".join(f.effect + (f" at {f.location}" if f.location else "")
                     + f" ({100 * explained_share(f):.0f} %)" for f in diag.findings) or "nothing"


def plot_rig_diagnosis(model, out_dir, diag, rod: str) -> list[Path]:
    """``diagnosis_rig.png``: residuals against load mass per load axis (one panel each, one colour per gauge,
    filled = loading, hollow = unloading) before and after modelling the findings, and both against time."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = model.data
    before, after = model.base_resid * 1e3, model.resid * 1e3
    axes_present = [int(a) for a in np.unique(d.axis)]
    n = len(axes_present)
    mosaic = [[f"b{a}" for a in axes_present for _ in range(2)], [f"a{a}" for a in axes_present for _ in range(2)],
              ["tb"] * n + ["ta"] * n]
    fig, ax = plt.subplot_mosaic(mosaic, figsize=(4.2 * n + 1, 9.5), constrained_layout=True)
    for a in axes_present:
        for key, r, when in ((f"b{a}", before, "before"), (f"a{a}", after, "after")):
            _residual_vs_load(ax[key], d, r, a)
            ax[key].set_title(f"load along {'xyz'[a]}_T: {when}", fontsize=10)
    for key, r, when in (("tb", before, "before (the simulated compliance)"), ("ta", after, "after (with the findings)")):
        _residual_vs_time(ax[key], d, r)
        ax[key].set_title(f"residuals vs time, {when}", fontsize=10)
    handles = {}
    for a in axes_present:
        for h, lab in zip(*ax[f"b{a}"].get_legend_handles_labels()):
            handles.setdefault(lab, h)
    order = sorted(handles, key=lambda lab: (lab.endswith("unload"), lab))
    fig.legend([handles[k] for k in order], order, loc="outside lower center", ncol=6, fontsize=8, markerscale=2)
    fig.suptitle(f"rod {rod}: {diag.verdict}; found {_finding_names(diag)}; rms {diag.rms_before_mm * 1e3:.2f} -> "
                 f"{diag.rms_after_mm * 1e3:.2f} um (noise {diag.noise_mm * 1e3:.2f} um)", fontsize=11)
    return [atomic_write_figure(Path(out_dir) / "diagnosis_rig.png", fig, 110)]


_GAUGE_COLOURS = ("tab:blue", "tab:orange", "tab:green")


def _residual_vs_load(ax, d, r, axis: int) -> None:
    for c in np.unique(d.comp):
        for unload in (False, True):
            m = (d.axis == axis) & (d.comp == c) & (d.unload == unload) & ~d.reference
            if not m.any():
                continue
            colour = _GAUGE_COLOURS[int(c) % 3]
            ax.plot(np.abs(d.mass[m]) + (0.012 if unload else -0.012) + 0.004 * (int(c) - 1), r[m], "o", ms=2.5,
                    alpha=0.5, color=colour, mfc="none" if unload else colour, mew=0.6,
                    label=f"gauge {'xyz'[int(c)]}, {'unload' if unload else 'load'}")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("load mass [kg]")
    ax.set_ylabel("residual [um]")
    ax.grid(True, lw=0.3)


def _residual_vs_time(ax, d, r) -> None:
    for c in np.unique(d.comp):
        m = d.comp == c
        ax.plot(d.t_abs[m], r[m], ".", ms=1.5, alpha=0.5, color=_GAUGE_COLOURS[int(c) % 3],
                label=f"gauge {'xyz'[int(c)]}")
    ax.axhline(0, color="k", lw=0.8)
    ax.set_xlabel("time since the recording started [s]")
    ax.set_ylabel("residual [um]")
    ax.legend(fontsize=7, markerscale=4)
    ax.grid(True, lw=0.3)


def plot_campaign_diagnosis(diag, fits, out_dir, noise_mm: float) -> list[Path]:
    """``diagnosis_campaign.png``: residual length of every point before (the identified model) and after (with
    the found physics), grouped by clamping position with the findings marked; below, the same against each
    joint angle and against time, with the part the found physics explains (``|r_before - r_after|``)
    overlaid. With validation points, the validation error distribution of the nominal, identified and
    corrected models (``error_distributions.png``)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    lengths = _campaign_lengths(fits)
    n_j = 0 if fits.q_deg is None else fits.q_deg.shape[1]
    mosaic = [["points"] * max(n_j, 1)] + ([[f"q{k}" for k in range(n_j)]] if n_j else [])
    if fits.time_s is not None:
        mosaic.append(["time"] * max(n_j, 1))
    heights = [1.6] + [1.0] * (len(mosaic) - 1)
    fig, ax = plt.subplot_mosaic(mosaic, figsize=(14, 4.4 + 2.8 * (len(mosaic) - 1)), height_ratios=heights,
                                 constrained_layout=True)
    _residuals_per_point(ax["points"], diag, fits, lengths, noise_mm)
    for k in range(n_j):
        _residuals_against(ax[f"q{k}"], fits.q_deg[:, k], lengths, f"q{k + 1} [deg]")
    if fits.time_s is not None:
        _residuals_against(ax["time"], fits.time_s, lengths, "time of the point [s]")
    fig.suptitle(f"campaign diagnosis: {diag.verdict}; found {_finding_names(diag)}; rms "
                 f"{diag.rms_before_mm * 1e3:.1f} -> {diag.rms_after_mm * 1e3:.1f} um", fontsize=11)
    out = [atomic_write_figure(Path(out_dir) / "diagnosis_campaign.png", fig, 100)]
    if fits.validation_errors_mm is not None:
        e = fits.validation_errors_mm
        out.append(plot_error_distributions({"nominal": e["nominal"], "identified": e["before"],
                                             "with the found physics": e["after"]}, out_dir,
                                            "validation errors: the found physics modelled"))
    return out


def _campaign_lengths(fits) -> dict:
    """Residual length per point [um]: before, after (NaN where dropped) and the explained part."""
    before_v = np.asarray(fits.before.residuals_mm) * 1e3
    after_v = np.full(before_v.shape, np.nan)
    if fits.after is not None:
        after_v[fits.kept] = np.asarray(fits.after.residuals_mm) * 1e3
    return {"before": np.linalg.norm(before_v, axis=1), "after": np.linalg.norm(after_v, axis=1),
            "explained": np.linalg.norm(before_v - after_v, axis=1)}


def _residuals_per_point(ax, diag, fits, lengths: dict, noise_mm: float) -> None:
    before, after = lengths["before"], lengths["after"]
    x = np.arange(before.size)
    _shade_positions(ax, fits, diag)
    ax.plot(x, before, "o", ms=4, color="tab:red", label=f"identified model: rms {diag.rms_before_mm * 1e3:.1f} um")
    if fits.after is not None:
        ax.plot(x, after, "s", ms=4, mfc="none", color="tab:blue",
                label=f"with the found physics: rms {diag.rms_after_mm * 1e3:.1f} um")
        dropped = ~fits.kept
        if dropped.any():
            ax.plot(x[dropped], before[dropped], "x", ms=10, mew=2, color="k", label="dropped as outlier")
        ax.plot([], [], "^", ms=4, color="tab:green", label="explained by the found physics (panels below)")
    ax.axhline(noise_mm * 1e3 * np.sqrt(3), color="k", lw=0.8, ls=":",
               label=f"expected length from device noise ({noise_mm * 1e3:.1f} um per reading)")
    _log_axis(ax)
    ax.set_xticks(x)
    ax.set_xticklabels(fits.labels, rotation=90, fontsize=6)
    ax.set_ylabel("residual length per point [um]")
    ax.legend(fontsize=8, loc="lower center", bbox_to_anchor=(0.5, 1.0), ncol=5, frameon=False)
    ax.grid(True, lw=0.3, which="both")


def _residuals_against(ax, x, lengths: dict, xlabel: str) -> None:
    """Residual length before / after against one variable, the explained part overlaid."""
    ax.plot(x, lengths["before"], "o", ms=3, color="tab:red", alpha=0.7, label="identified model")
    if np.isfinite(lengths["after"]).any():
        ax.plot(x, lengths["after"], "s", ms=3, mfc="none", color="tab:blue", label="with the found physics")
        ax.plot(x, lengths["explained"], "^", ms=3, color="tab:green", alpha=0.8,
                label="explained by the found physics")
    _log_axis(ax)
    ax.set_xlabel(xlabel)
    ax.set_ylabel("um")
    ax.grid(True, lw=0.3, which="both")


def _log_axis(ax) -> None:
    from matplotlib.ticker import FuncFormatter
    ax.set_yscale("log")
    ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.yaxis.set_minor_formatter(FuncFormatter(lambda v, _: f"{v:g}" if f"{v:g}"[0] in "25" else ""))


def _shade_positions(ax, fits, diag) -> None:
    """Alternate grey bands per clamping position; a position a finding names is shaded orange."""
    named = {f.location.split(":")[1] for f in diag.findings if (f.location or "").startswith("position:")}
    for j in np.unique(fits.position):
        m = np.nonzero(fits.position == j)[0]
        colour = "moccasin" if str(j) in named else ("0.92" if j % 2 else "white")
        ax.axvspan(m.min() - 0.5, m.max() + 0.5, color=colour, zorder=0)
        ax.text(m.mean(), 0.98, f"position {j}", transform=ax.get_xaxis_transform(), ha="center", va="top",
                fontsize=8)
