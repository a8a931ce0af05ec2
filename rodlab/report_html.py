"""One self-contained HTML page of a run folder (``rodlab report``): figures embedded as data URIs."""
from __future__ import annotations

import base64
import html
import json
from pathlib import Path

from .errors import RodlabError
from .fileio import atomic_write_text

__all__ = ["write_report", "render_report", "CSS", "img_tag"]

CSS = """body{font-family:system-ui,-apple-system,Segoe UI,Roboto,sans-serif;max-width:1100px;margin:2em auto;
padding:0 1em;color:#222}h1{font-size:1.6em}h2{border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:2em}
table{border-collapse:collapse;margin:.6em 0}td,th{border:1px solid #ccc;padding:.25em .6em;text-align:right}
th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}img{max-width:100%;border:1px solid #eee;
margin:.4em 0}.grid{display:grid;grid-template-columns:1fr 1fr;gap:.6em}.note{color:#555;font-size:.92em}
code{background:#f4f4f4;padding:0 .2em}"""


def img_tag(run: Path, rel: str | None, alt: str) -> str:
    """An ``<img>`` with the PNG ``run/rel`` embedded as a data URI (a note if it is missing)."""
    if not rel:
        return ""
    p = run / rel
    if not p.exists():
        return f"<p class='note'>missing figure {html.escape(rel)}</p>"
    data = base64.b64encode(p.read_bytes()).decode("ascii")
    return f"<img alt='{html.escape(alt)}' src='data:image/png;base64,{data}'>"


def _matrix(m, unit, scale=1e3) -> str:
    rows = "".join("<tr>" + "".join(f"<td>{round(v * scale, 3) + 0.0:+.3f}</td>" for v in row) + "</tr>" for row in m)
    return f"<table><tr><th colspan=3>{html.escape(unit)}</th></tr>{rows}</table>"


def render_report(run_dir) -> str:
    run = Path(run_dir)
    try:
        s = json.loads((run / "run.json").read_text())
    except FileNotFoundError as e:
        raise RodlabError(f"{run}: no run.json here; run `rodlab demo -o {run}` first") from e
    st, files = s["stages"], s.get("files", {})
    d = s["design"]
    parts = [f"<!doctype html><html lang=en><head><meta charset=utf-8><title>rodlab run: rod {html.escape(d['name'])}"
             f"</title><style>{CSS}</style></head><body>",
             f"<h1>rodlab run: rod {html.escape(d['name'])} on a TX90</h1>",
             "<p class=note>Rod 1# of Wan et al. (2023) from the built-in design; a simulated stiffness rig and a "
             "simulated MultiCal campaign stand in for the hardware. Stage times: "
             + ", ".join(f"{k} {v:.1f} s" for k, v in s.get("timings_s", {}).items()) + ".</p>"]
    parts.append("<h2>1. Design</h2><table><tr><th>quantity</th><th>value</th></tr>"
                 f"<tr><td>L1 / L2 / gamma</td><td>{d['L1_mm']:g} mm / {d['L2_mm']:g} mm / {d['gamma_deg']:g} deg</td></tr>"
                 f"<tr><td>tubes</td><td>{html.escape(d['pipe_I']['material'])} {d['pipe_I']['outer_diameter_mm']:g} x "
                 f"{d['pipe_I']['wall_mm']:g} mm</td></tr><tr><td>bend</td><td>{html.escape(d['bend']['material'])}, "
                 f"R {d['bend']['radius_mm']:g} mm</td></tr><tr><td>mass</td><td>{st['design']['mass_kg'] * 1e3:.1f} g</td></tr>"
                 "</table>")
    views = files.get("cad_views", [])
    parts.append("<h2>2. CAD</h2>" + ("<div class=grid>" + "".join(img_tag(run, v, f"CAD view {v}") for v in views) + "</div>"
                                        if views else f"<p class=note>{html.escape(st['cad'].get('skipped', ''))}</p>"))
    fe = st["fea"]
    parts.append(f"<h2>3. Compliance ({html.escape(fe['model'])})</h2><div class=grid>"
                 f"<div>C_F {_matrix(fe['C_F_mm_per_N'], 'um/N')}"
                 f"</div><div>C_g {_matrix(fe['C_g_mm_per_g0'], 'um per g0')}</div></div>"
                 f"<p>c_rod (Eq. 23) = {fe['c_rod_um']:.1f} um (closed form: {st['design']['c_rod_um_calc']:.1f} um). "
                 "Closed form / FEA on the diagonal of C_F: " + ", ".join(f"{v:.3f}" for v in fe["calc_over_fea_diag"])
                 + " (the closed form misses shear, the bend's ovalisation and the sleeves' load transfer; verification"
                 " in docs/fea.md).</p>" + img_tag(run, files.get("fea_deformed"), "deformed shape"))
    ft = st["fit"]
    parts.append(f"<h2>4. Stiffness rig</h2><p>Recording with a concealed effect; fitted r_rod (Eq. 21) = "
                 f"{ft['r_rod']:.4f}, noise {ft['noise_um']:.2f} um per reading.</p>" + img_tag(run, files.get("fig8"), "Fig. 8"))
    dg = st["diagnose"]
    rows = "".join(f"<tr><td>{html.escape(f['effect'])}</td><td>{html.escape(str(f['location']))}</td><td>"
                   + html.escape(", ".join(f"{k} = {v:.4g}" for k, v in f["parameters"].items() if isinstance(v, (int, float))))
                   + f"</td><td>{f['rms_before_mm'] * 1e3:.2f} -> {f['rms_after_mm'] * 1e3:.2f}</td><td>"
                   f"{html.escape(f['explanation'])}</td></tr>" for f in dg["findings"])
    parts.append(f"<h2>5. Diagnosis</h2><p>Verdict <b>{html.escape(dg['verdict'])}</b>; noise {dg['noise_mm'] * 1e3:.2f} um; "
                 f"rms {dg['rms_before_mm'] * 1e3:.2f} -> {dg['rms_after_mm'] * 1e3:.2f} um. The rig truth was: "
                 f"{html.escape(st['rig']['concealed_effect'])} (s_bend {st['rig']['s_bend_rad_per_Nm']:.3g}, s_torsion "
                 f"{st['rig']['s_torsion_rad_per_Nm']:.3g} rad/(N m)); the corrected compliance matches the true C_F to "
                 f"{dg['corrected_vs_true_max_rel']:.1e}.</p><table><tr><th>effect</th><th>location</th><th>parameters</th>"
                 f"<th>rms um</th><th>physics</th></tr>{rows}</table>" + img_tag(run, files.get("diagnosis"), "diagnosis"))
    t3 = st["calibrate"]["table3"]
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{v['mean_mm']:.3f}</td><td>{v['max_mm']:.3f}</td>"
                   f"<td>{v['median_mm']:.3f}</td><td>{v['sd_mm']:.3f}</td></tr>" for k, v in t3.items())
    parts.append("<h2>6. Calibration (the paper's Table 3 and Fig. 10)</h2><table><tr><th>method</th><th>Mean/[mm]</th>"
                 f"<th>Max/[mm]</th><th>Median/[mm]</th><th>SD/[mm]</th></tr>{rows}</table>"
                 + img_tag(run, files.get("fig10"), "Fig. 10"))
    sw = st["sweep"]
    parts.append(f"<h2>7. L1 / L2 sweep</h2><p>{sw['designs']} designs ({sw['ok']} valid); stiffest L1 = "
                 f"{sw['stiffest']['L1_mm']:g} mm, L2 = {sw['stiffest']['L2_mm']:g} mm, c_rod "
                 f"{sw['stiffest']['c_rod_um']:.0f} um.</p>" + img_tag(run, files.get("sweep"), "sweep heat maps"))
    if "study" in st:
        parts.append(_study_section(run, st["study"], files))
    parts.append("</body></html>")
    return "\n".join(parts)


def _pct(share) -> str:
    return "—" if share is None or share != share else f"{100 * share:.0f}"


def _study_section(run: Path, sy: dict, files: dict) -> str:
    """8. The study: predicted calibration accuracy of the paper's carbon rods per method."""
    rows = "".join(
        f"<tr><td>{html.escape(str(r['design']))}</td><td>{r['c_rod_um']:.0f}</td><td>{r['mass_kg'] * 1e3:.0f}</td>"
        f"<td>{html.escape(str(r['method']))}</td><td>{r['mean_mm']:.3f}</td><td>{r['mean_p05_mm']:.3f}-"
        f"{r['mean_p95_mm']:.3f}</td><td>{r['max_mm']:.3f}</td><td>{_pct(r['share_deflection'])} / "
        f"{_pct(r['share_identification'])} / {_pct(r['share_noise'])}</td></tr>" for r in sy["rows"])
    return (f"<h2>8. Which rod? Predicted calibration accuracy (rodlab study)</h2><p><b>Recommendation.</b> "
            f"{html.escape(sy['recommendation'])}</p><p class=note>{len(sy['designs'])} designs "
            f"({html.escape(', '.join(sy['designs']))}) on the TX90, {sy['replicates']} simulated campaigns each "
            f"(a design study uses 20: <code>rodlab study</code>); compliance: {html.escape(sy['compliance'])}. "
            "Mean validation error after calibration, its 5-95 % band over the campaigns, and the error budget: the "
            "shares of the mean-square error from the rod's deflection left after compensation, the identification "
            "and the validation instrument's noise. The whole study: <code>study/study.html</code>.</p>"
            "<table><tr><th>design</th><th>c_rod um</th><th>mass g</th><th>method</th><th>mean mm</th>"
            f"<th>90 % band mm</th><th>max mm</th><th>budget % (defl. / ident. / noise)</th></tr>{rows}</table>"
            + img_tag(run, files.get("study_pareto"), "study Pareto fronts"))


def write_report(run_dir, out=None) -> Path:
    return atomic_write_text(Path(out) if out else Path(run_dir) / "report.html", render_report(run_dir))
