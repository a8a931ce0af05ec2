"""Calibration figures: residuals per clamping position; validation error distributions per method
(the paper's Fig. 10 / 11)."""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from rodlab.fileio import atomic_write_bytes

__all__ = ["plot_residuals", "plot_error_distributions"]


def _save(fig, path) -> Path:
    import matplotlib.pyplot as plt
    buf = io.BytesIO()
    fig.savefig(buf, dpi=120)
    plt.close(fig)
    return atomic_write_bytes(path, buf.getvalue())


def plot_residuals(res, camp, out_dir) -> Path:
    """Residual components [um] of every point, grouped by clamping position."""
    import matplotlib
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


def plot_error_distributions(args, rows, out) -> Path:
    """Histogram-like distributions (box plots) of the validation errors per method."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from rodlab.calibrate import ModelParams, read_points, resolve_robot, validate
    robot = resolve_robot(args.robot)
    pts = read_points(args.validate, robot.n)
    data, labels = [validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)[1]], ["nominal"]
    for name, res, _, _ in rows:
        data.append(validate(robot, res.params, pts)[1])
        labels.append(name)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    axes[0].boxplot(data[1:], tick_labels=labels[1:], showmeans=True)
    axes[0].set_ylabel("validation position error [mm]")
    axes[0].set_title("after calibration, per compensation method", fontsize=10)
    bins = np.linspace(0, max(float(np.max(d)) for d in data[1:]) * 1.05, 25)
    for d, lab in zip(data[1:], labels[1:]):
        axes[1].hist(d, bins=bins, histtype="step", lw=1.2, label=f"{lab}: mean {d.mean():.3f} mm")
    axes[1].set_xlabel("validation position error [mm]")
    axes[1].set_ylabel("points")
    axes[1].legend(fontsize=8)
    for a in axes:
        a.grid(True, lw=0.3)
    fig.suptitle(f"validation errors on {len(data[0])} points (nominal model: mean {data[0].mean():.3f} mm)",
                 fontsize=11)
    p = Path(out)
    return _save(fig, p / "error_distributions.png" if p.suffix != ".png" else p)
