"""A finished study's files: ``study.csv``, ``pareto.png``, ``heatmaps.png`` (grids), ``study.html``,
``study.json`` — written by ``rodlab study`` and by the demo's study stage alike."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from rodlab.core.fileio import atomic_write_json, atomic_write_text, json_safe
from rodlab.core.view3d import start_offscreen_check
from rodlab.app.report.views import frame_views

from .plots import plot_heatmaps, plot_pareto
from .report import write_study_report
from .run import StudyRun, spec_dict
from .design_warnings import DesignWarning, study_warnings, warning_lines
from .table import Recommendation, recommend, study_table

__all__ = ["StudyOutputs", "write_study_outputs", "best_method"]

#: the method a design's headline accuracy is quoted for: the best compensation studied
_PREFERENCE = ("meas", "fea", "calc", "none")


@dataclass(frozen=True)
class StudyOutputs:
    """What :func:`write_study_outputs` wrote: the study table (one row per design and method), the
    recommendation, the figures ({caption: file name in the folder}), the files and the warnings on designs."""

    table: object
    recommendation: Recommendation
    figures: dict
    files: tuple
    warnings: tuple[DesignWarning, ...] = ()


def best_method(methods) -> str:
    """The headline method of a study: Meas, else FEA, Calc, None among those studied."""
    return next((m for m in _PREFERENCE if m in methods), tuple(methods)[0])


def write_study_outputs(out_dir, run: StudyRun, robot_name: str, grid: bool, header: dict,
                        extra_json: dict | None = None, designs: dict | None = None) -> StudyOutputs:
    """Write the study's files into ``out_dir`` (atomically each); ``header`` {label: text} heads the page,
    ``extra_json`` is merged into ``study.json``; ``designs`` {label: RodDesign}: the recommended one is drawn in
    3-D (its frame centreline, ``recommended.vtp`` and a picture of its weakest load case)."""
    out = Path(out_dir)
    if designs:
        start_offscreen_check()                  # the 3-D views' probe runs while the figures below are drawn
    df = study_table(run)
    rec = recommend(df)
    warns = tuple(study_warnings(df, run.spec.priors.rod_slip if run.spec.priors is not None else 0.0))
    atomic_write_text(out / "study.csv", df.to_csv(index=False))
    title = (f"{robot_name}, {run.spec.replicates} simulated campaigns per design" if run.spec.monte_carlo
             else f"{robot_name}, linear predictor ({run.spec.draws} draws per design)")
    pareto = plot_pareto(df, out / "pareto.png", best_method(run.spec.methods), title)
    figs = {"Pareto fronts: predicted accuracy vs mass and vs reach": pareto.name}
    heat = plot_heatmaps(df, out / "heatmaps.png", title) if grid else None
    if heat is not None:
        figs["Predicted mean error over L1 x L2"] = heat.name
    extra = _recommended_views(out, rec, designs or {})
    figs.update({f"Recommended design {rec.design} under a unit force at the ball (frame model, displacement "
                 f"x the factor written; all load cases in {extra[0]})": p for p in extra[1:]})
    write_study_report(out, df, rec.text, figs, header, run.spec.monte_carlo, warning_lines(warns))
    atomic_write_json(out / "study.json", json_safe({"format": "rodlab.study/1", "recommendation": rec.to_dict(),
                                                     "warnings": [w.to_dict() for w in warns],
                                                     "spec": spec_dict(run.spec), "robot": robot_name,
                                                     "designs": len(run.setups), **(extra_json or {})}))
    files = ("study.csv", *figs.values(), "study.html", "study.json", *extra[:1])
    return StudyOutputs(df, rec, figs, files, warns)


def _recommended_views(out: Path, rec: Recommendation, designs: dict) -> tuple:
    """(field file, picture names) of the recommended design's frame centreline; () without one."""
    design = designs.get(rec.design)
    if design is None:
        return ()
    views = frame_views(design, out / "recommended.vtp", loads="weakest")
    return (views.fields.name, *(p.name for p in views.pngs))
