"""``DIR/study.html``: the study as one self-contained page (figures embedded)."""
from __future__ import annotations

import html
import math
from pathlib import Path

from rodlab.core.fileio import atomic_write_text
from rodlab.app.report.html import CSS, img_tag

__all__ = ["write_study_report", "has_message"]


def _f(v, fmt):
    try:
        return "—" if v is None or (isinstance(v, float) and math.isnan(v)) else format(v, fmt)
    except (TypeError, ValueError):
        return html.escape(str(v))


def _design_table(df) -> str:
    head = ("<tr><th>design</th><th>material</th><th>tube</th><th>c_rod um</th><th>mass g</th><th>O1</th>"
            "<th>thermal um/K</th><th>f1 Hz</th><th>tube margin</th><th>bond margin</th><th>status</th></tr>")
    rows = []
    for r in df.drop_duplicates("design").itertuples():
        rows.append(f"<tr><td>{html.escape(str(r.design))}</td><td>{html.escape(str(r.material))}</td>"
                    f"<td>{html.escape(str(r.tube))}</td><td>{_f(r.c_rod_um, '.1f')}</td>"
                    f"<td>{_f(r.mass_kg * 1e3 if r.mass_kg == r.mass_kg else float('nan'), '.0f')}</td>"
                    f"<td>{_f(r.O1, '.4f')}</td><td>{_f(r.thermal_um_per_K, '.2f')}</td><td>{_f(r.f1_Hz, '.1f')}</td>"
                    f"<td>{_f(r.tube_margin, '.0f')}</td><td>{_f(r.bond_margin, '.0f')}</td>"
                    f"<td>{html.escape(str(r.status))}{': ' + html.escape(str(r.message)) if has_message(r.message) else ''}"
                    "</td></tr>")
    return f"<table>{head}{''.join(rows)}</table>"


def _accuracy_table(df) -> str:
    head = ("<tr><th>design</th><th>method</th><th>mean mm</th><th>90 % band</th><th>max mm</th><th>median mm</th>"
            "<th>deflection</th><th>slip</th><th>identification</th><th>noise</th></tr>")
    ok = df[df["method"].notna()]
    rows = "".join(
        f"<tr><td>{html.escape(str(r.design))}</td><td>{html.escape(str(r.method))}</td><td>{r.mean_mm:.4f}</td>"
        f"<td>{r.mean_p05_mm:.4f}-{r.mean_p95_mm:.4f}</td><td>{r.max_mm:.3f}</td><td>{r.median_mm:.4f}</td>"
        f"<td>{_f(100 * r.share_deflection, '.0f')} %</td><td>{_f(100 * r.share_slip, '.0f')} %</td>"
        f"<td>{_f(100 * r.share_identification, '.0f')} %</td>"
        f"<td>{_f(100 * r.share_noise, '.0f')} %</td></tr>" for r in ok.itertuples())
    return f"<table>{head}{rows}</table>"


def write_study_report(out_dir, df, recommendation: str, figures: dict, header: dict,
                       monte_carlo: bool = False, warnings: list[str] = ()) -> Path:
    """Write ``out_dir/study.html``; ``figures`` {caption: file name in out_dir}; ``header`` {label: text};
    ``monte_carlo``: the numbers are of simulated campaigns (else of the linear predictor); ``warnings``: the
    sentences on designs (:func:`~.design_warnings.study_warnings`), under the recommendation."""
    out = Path(out_dir)
    parts = [f"<!doctype html><html lang=en><head><meta charset=utf-8><title>rodlab study</title><style>{CSS}"
             "</style></head><body><h1>rodlab study: which rod gives the best calibration?</h1>",
             f"<p><b>Recommendation.</b> {html.escape(recommendation)}</p>"
             + ("<p><b>Warnings.</b></p><ul>" + "".join(f"<li>{html.escape(w)}</li>" for w in warnings) + "</ul>"
                if warnings else "") + "<table>"
             + "".join(f"<tr><td>{html.escape(k)}</td><td style='text-align:left'>{html.escape(str(v))}</td></tr>"
                       for k, v in header.items()) + "</table>"]
    for caption, name in figures.items():
        parts.append(f"<h2>{html.escape(caption)}</h2>" + img_tag(out, name, caption))
    how = ("averaged over the simulated campaigns; the band is the 5-95 % range of the campaigns' mean error"
           if monte_carlo else "predicted by the linear predictor (the identification's covariance and the "
           "compensation's bias propagated to the validation points; draws of that linear model, not simulated "
           "campaigns); the band is the 5-95 % range of a campaign's mean error over those draws")
    parts.append("<h2>Predicted calibration accuracy and its error budget</h2><p class=note>Validation errors after "
                 f"calibration, {how}. Budget: the shares of the mean-square error left by the rod's deflection after "
                 "compensation, by the rod's slip (its non-repeatable deflection, --rod-slip: no compensation removes it), "
                 "by the identification (campaign noise through the observability), and by the "
                 "validation instrument's own noise.</p>" + _accuracy_table(df))
    parts.append("<h2>Designs</h2><p class=note>Thermal growth of the tool vector per kelvin; f1 the first natural "
                 "frequency on the flange (frame model); margins are allowable / peak stress under the campaign's "
                 "contact force and 1 g in any direction.</p>" + _design_table(df))
    parts.append("</body></html>")
    return atomic_write_text(out / "study.html", "\n".join(parts))


def has_message(message) -> bool:
    """A row's message is there (not empty, not NaN from the CSV)."""
    return isinstance(message, str) and bool(message.strip())
