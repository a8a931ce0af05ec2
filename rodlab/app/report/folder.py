"""A report of any rodlab output: the results found in a folder (``rodlab report DIR``) or the files one command
just wrote (``--report``), each rendered by its format's section with its figures beside it."""
from __future__ import annotations

import json
import logging
from datetime import datetime, timezone
from fnmatch import fnmatch
from pathlib import Path

from ... import __version__
from ...core.errors import RodlabError
from ...core.fileio import atomic_write_text
from .html import esc, figure, page
from .sections import FORMAT_MASS, FORMAT_SWEEP, SECTIONS, Source
from .demo import is_run_folder, render_run

__all__ = ["classify", "discover", "render_sources", "write_sources_report", "write_folder_report", "CAPTIONS"]

log = logging.getLogger(__name__)

#: what each figure rodlab writes shows (by file name; ``*`` patterns allowed)
CAPTIONS = {
    "view_*.png": "CAD view of the rod assembly, parts coloured",
    "*3d_F?.png": "FEA fields in 3-D (rodlab view): the deformed rod (exaggerated) over its undeformed outline under a "
                  "unit force at the ball, coloured by von Mises stress (solid model: at the nodes; frame: the "
                  "sections' outer fibre)",
    "deformed.png": ("solid FEA: deformed shape under self-weight along -z_T (exaggerated, the largest displacement "
                     "in the legend), coloured by part over the undeformed rod"),
    "fig8.png": "the paper's Fig. 8: load-deflection lines per axis with the fitted slopes; residuals below",
    "diagnosis_rig.png": "rig diagnosis: residuals per load axis and gauge before and after modelling the findings, "
                         "and against time",
    "diagnosis_campaign.png": "campaign diagnosis: residual length per point by clamping position, against each "
                              "joint angle and time; triangles: the part the found physics explains",
    "residuals.png": "calibration residuals per clamping position",
    "error_distributions.png": "validation errors: box plots after calibration and cumulative distributions",
    "*fig10.png": "the paper's Fig. 10: validation errors per compensation method",
    "*sweep.png": "sweep heat maps: c_rod and mass over L1 x L2",
    "pareto.png": "design study: predicted calibration error against mass and reach",
    "heatmaps.png": "design study: predicted error over the grid, one colour scale per method",
}
_SKIP_DIRS = {"cache", "chrome-profile", "__pycache__"}


def _caption(name: str) -> str:
    return next((c for pat, c in CAPTIONS.items() if fnmatch(name, pat)), name)


def classify(path: Path) -> Source | None:
    """The :class:`Source` a file holds, or None when it is not a rodlab result (inputs, images, unknown)."""
    path = Path(path)
    try:
        if path.suffix == ".png" or not path.is_file():
            return None
        with path.open("rb") as fh:
            first = fh.read(64).lstrip()[:1]
        if path.suffix == ".json" or first == b"{":          # a JSON result under another name (-o out.csv, -o figs)
            data = json.loads(path.read_text())
            if not isinstance(data, dict):
                return None
            fmt = data.get("format") or (FORMAT_MASS if {"parts", "total"} <= data.keys() else None)
            return Source(fmt, data, path) if fmt in SECTIONS else None
        if path.suffix == ".csv":
            with path.open() as fh:
                cols = set(fh.readline().strip().split(","))
            if {"L1_mm", "L2_mm", "c_rod_um", "status"} <= cols and "method" not in cols:
                import pandas as pd
                return Source(FORMAT_SWEEP, pd.read_csv(path), path)
    except (OSError, ValueError, UnicodeDecodeError) as e:
        log.warning("%s: not read for the report (%s)", path, e)
    return None


def discover(folder: Path, depth: int = 2) -> tuple[list[Source], list[Path]]:
    """Results and PNG figures in ``folder`` and its sub-folders (``depth`` levels; caches skipped)."""
    sources, figures = [], []
    for p in sorted(folder.iterdir()):
        if p.is_dir():
            if depth > 0 and p.name not in _SKIP_DIRS and not p.name.endswith(".cache"):
                s, f = discover(p, depth - 1)
                sources += s
                figures += f
        elif p.suffix == ".png":
            figures.append(p)
        else:
            src = classify(p)
            if src is not None:
                sources.append(src)
    return sources, figures


def _named_figures(src: Source) -> list[Path] | None:
    """The figures a result names as its own (``provenance.figures``, relative to its file: ``rig fit --png``),
    or None when it names none."""
    prov = src.data.get("provenance") if isinstance(src.data, dict) else None
    names = prov.get("figures") if isinstance(prov, dict) else None
    if not names or src.path is None:
        return None
    return [(src.path.parent / str(n)).resolve() for n in names]


def _claim(src: Source, figures: list[Path], used: set, reserved: set = frozenset()) -> list[Path]:
    """The figures ``src`` names as its own, else those of its section found in its folder (any folder for a
    result not written), not yet shown (figures another result names are left to it)."""
    named = _named_figures(src)
    if named is not None:
        mine = [f for f in figures if f.resolve() in named and f not in used]
        used.update(mine)
        return mine
    pats = SECTIONS[src.format].figures
    free = [f for f in figures if f not in used and f not in reserved]
    if src.path is None:
        mine = [f for f in free if any(fnmatch(f.name, p) for p in pats)]
    else:
        mine = [f for f in free if f.parent == src.path.parent
                and (f.stem == src.path.stem or any(fnmatch(f.name, p) for p in pats))]
    used.update(mine)
    return mine


def render_sources(sources: list[Source], figures: list[Path], title: str, intro: str = "",
                   base: Path | None = None) -> str:
    """The page: one section per result (in the order design -> compliance -> study -> calibration ->
    diagnosis), its figures beside it; figures no section claims at the end."""
    if not sources and not figures:
        raise RodlabError("nothing to report: no rodlab result (compliance, calibration, diagnosis, study, sweep, "
                          "comparison, mass) or figure here; run a command with -o / --json / --png into this folder")
    used: set = set()
    reserved = {f for src in sources for f in figures if f.resolve() in (_named_figures(src) or ())}
    body = []
    for i, src in enumerate(sorted(sources, key=lambda s: (SECTIONS[s.format].order, str(s.path))), 1):
        sec = SECTIONS[src.format]
        where = f" <span class=note>(<code>{esc(src.label(base))}</code>)</span>" if src.path else ""
        figs = _claim(src, figures, used, reserved)
        scale = 0.5 if src.format == FORMAT_MASS else None
        body.append(f"<h2>{i}. {esc(sec.title)}{where}</h2>" + sec.render(src)
                    + ("<div class=views>" if scale else "")
                    + "".join(figure(f, _caption(f.name), scale) for f in figs) + ("</div>" if scale else ""))
    rest = [f for f in figures if f not in used]
    if rest:
        body.append("<h2>Figures</h2>" + "".join(figure(f, _caption(f.name)) for f in rest))
    stamp = datetime.now(timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    return page(title, body, f"<p class=note>rodlab {esc(__version__)}, {stamp}. {intro}</p>")


def write_sources_report(out: Path, sources: list[Source], figures: list[Path], title: str, intro: str = "") -> Path:
    """Render and write the page atomically to ``out``."""
    return atomic_write_text(Path(out), render_sources(sources, figures, title, intro, Path(out).parent))


def write_folder_report(folder, out=None) -> Path:
    """``rodlab report DIR``: the demo's page for a demo folder, else every result found in ``folder``."""
    folder = Path(folder)
    if not folder.is_dir():
        raise RodlabError(f"{folder}: not a folder; give the folder a rodlab command wrote into")
    out = Path(out) if out else folder / "report.html"
    if is_run_folder(folder):
        return atomic_write_text(out, render_run(folder))
    sources, figures = discover(folder)
    return write_sources_report(out, sources, figures, f"rodlab results in {folder.resolve().name}",
                                f"Every result found in <code>{esc(folder)}</code>.")
