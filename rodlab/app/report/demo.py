"""The demo's page (``run.json``, format ``rodlab.run/1``): the main job end to end on one page."""
from __future__ import annotations

import html
import json
from pathlib import Path

from ...core.errors import RodlabError
from .demo_story import campaign_rod_note, conclusion_html, study_rod_note, terms_html
from .html import CSS, img_tag, matrix_table

__all__ = ["render_run", "is_run_folder", "read_run"]

#: scale of the CAD views on the page: the four views side by side at one pixel scale
_CAD_SCALE = 0.5
#: the 3-D field views (1400 px wide) at the page's full width, so that their captions and colour bar read
_VIEW_SCALE = 0.78


def is_run_folder(run_dir) -> bool:
    return (Path(run_dir) / "run.json").is_file()


def _cad_views(run: Path, views: list) -> str:
    return "<div class=views>" + "".join(f"<figure>{img_tag(run, v, f'CAD view {v}', _CAD_SCALE)}</figure>"
                                         for v in views) + "</div>"


def _fea_views(run: Path, files: dict, fea: dict) -> str:
    """The FEA's fields in 3-D (``rodlab view`` pictures of the unit forces), or why they are missing."""
    fields = fea.get("fields")
    if not fields:
        return ""
    head = (f"<p>The fields of the unit forces at the ball in 3-D: the deformed rod (exaggerated) over its undeformed "
            f"outline, coloured by von Mises stress (solid model: at the nodes; frame: the sections' outer fibre, from the "
            f"beam's section forces); all six load cases are in "
            f"<code>{html.escape(fields)}</code> for ParaView or <code>rodlab view</code>.</p>")
    views = files.get("fea_views") or []
    if not views:
        return head + f"<p class=note>No pictures: {html.escape(fea.get('views_note') or 'not rendered')}</p>"
    return head + "<div class=views>" + "".join(f"<figure>{img_tag(run, v, f'3-D view {v}', _VIEW_SCALE)}</figure>"
                                               for v in views) + "</div>"


def render_run(run_dir) -> str:
    """The demo folder ``run_dir`` (with ``run.json``) as one HTML page."""
    run = Path(run_dir)
    s = read_run(run)
    st, files = s["stages"], s.get("files", {})
    parts = [_head(s), _design_section(s["design"], st), _cad_section(run, st, files), _fea_section(run, st, files),
             _fea_views(run, files, st["fea"]), _rig_section(run, st, files), _diagnosis_section(run, st, files),
             _calibration_section(run, st, files), _sweep_section(run, st, files)]
    if "study" in st:
        parts.append(_study_section(run, st["study"], files, study_rod_note(st)))
    parts.append("</body></html>")
    return "\n".join(parts)


def _head(s: dict) -> str:
    d, st = s["design"], s["stages"]
    return (f"<!doctype html><html lang=en><head><meta charset=utf-8><title>rodlab run: rod {html.escape(d['name'])}"
            f"</title><style>{CSS}</style></head><body>\n"
            f"<h1>rodlab run: rod {html.escape(d['name'])} on a TX90</h1>\n"
            "<p class=note>Rod 1# of Wan et al. (2023) from the built-in design; a simulated stiffness rig and a "
            "simulated MultiCal campaign stand in for the hardware. Stage times: "
            + ", ".join(f"{k} {v:.1f} s" for k, v in s.get("timings_s", {}).items()) + ".</p>\n"
            + conclusion_html(st) + "\n" + terms_html())


def _design_section(d: dict, st: dict) -> str:
    return ("<h2>1. Design</h2><table><tr><th>quantity</th><th>value</th></tr>"
            f"<tr><td>L1 / L2 / gamma</td><td>{d['L1_mm']:g} mm / {d['L2_mm']:g} mm / {d['gamma_deg']:g} deg</td></tr>"
            f"<tr><td>tubes</td><td>{html.escape(d['pipe_I']['material'])} {d['pipe_I']['outer_diameter_mm']:g} x "
            f"{d['pipe_I']['wall_mm']:g} mm</td></tr><tr><td>bend</td><td>{html.escape(d['bend']['material'])}, "
            f"R {d['bend']['radius_mm']:g} mm</td></tr><tr><td>mass</td><td>{st['design']['mass_kg'] * 1e3:.1f} g</td></tr>"
            "</table>")


def _cad_section(run: Path, st: dict, files: dict) -> str:
    views = files.get("cad_views", [])
    return "<h2>2. CAD</h2>" + (_cad_views(run, views) if views
                                else f"<p class=note>{html.escape(st['cad'].get('skipped', ''))}</p>")


def _fea_section(run: Path, st: dict, files: dict) -> str:
    fe = st["fea"]
    return (f"<h2>3. Compliance ({html.escape(fe['model'])})</h2><div class=grid>"
            f"<div><b>C_F</b>: ball displacement per tip force {matrix_table(fe['C_F_mm_per_N'], 'um/N', 'force')}"
            f"</div><div><b>C_g</b>: ball displacement under the rod's own weight, per unit of gravity along each "
            f"axis {matrix_table(fe['C_g_mm_per_g0'], 'um per g0', 'gravity')}</div></div>"
            f"<p>c_rod (compliance index, Eq. 23) = {fe['c_rod_um']:.1f} um (closed form: "
            f"{st['design']['c_rod_um_calc']:.1f} um). "
            "Closed form / FEA on the diagonal of C_F: " + ", ".join(f"{v:.3f}" for v in fe["calc_over_fea_diag"])
            + " (the closed form misses shear, the bend's ovalisation and the sleeves' load transfer; verification"
            " in docs/fea.md).</p>" + img_tag(run, files.get("fea_deformed"), "deformed shape"))


def _rig_section(run: Path, st: dict, files: dict) -> str:
    ft = st["fit"]
    return (f"<h2>4. Stiffness rig</h2><p>Recording with a concealed effect; fitted r_rod (measured / "
            f"simulated compliance, Eq. 21) = "
            f"{ft['r_rod']:.4f}, noise {ft['noise_um']:.2f} um per reading.</p>" + img_tag(run, files.get("fig8"), "Fig. 8"))


def _diagnosis_section(run: Path, st: dict, files: dict) -> str:
    dg = st["diagnose"]
    rows = "".join(f"<tr><td>{html.escape(f['effect'])}</td><td>{html.escape(str(f['location'] or '-'))}</td><td>"
                   + html.escape(", ".join(f"{k} = {v:.4g}" for k, v in f["parameters"].items()
                                           if isinstance(v, (int, float)) and abs(v) > 1e-15))
                   + f"</td><td>{html.escape(_evidence(f))}</td><td>"
                   f"{html.escape(f['explanation'])}</td></tr>" for f in dg["findings"])
    return (f"<h2>5. Diagnosis</h2><p>Verdict <b>{html.escape(dg['verdict'])}</b>; noise {dg['noise_mm'] * 1e3:.2f} um; "
            f"rms {dg['rms_before_mm'] * 1e3:.2f} -> {dg['rms_after_mm'] * 1e3:.2f} um. The truth was "
            f"{html.escape(st['rig']['concealed_effect'])}; the corrected compliance differs from the true "
            f"C_F by at most {100 * dg['corrected_vs_true_max_rel']:.2f} % of its largest entry.</p>"
            "<table><tr><th>effect</th><th>location</th><th>parameters</th>"
            f"<th>what it explains</th><th>physics</th></tr>{rows}</table>"
            + img_tag(run, files.get("diagnosis"), "diagnosis") + _update_table(st))


def _calibration_section(run: Path, st: dict, files: dict) -> str:
    t3 = st["calibrate"]["table3"]
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{v['mean_mm']:.3f}</td><td>{v['max_mm']:.3f}</td>"
                   f"<td>{v['median_mm']:.3f}</td><td>{v['sd_mm']:.3f}</td></tr>" for k, v in t3.items())
    return ("<h2>6. Calibration (the paper's Table 3 and Fig. 10)</h2>" + campaign_rod_note(st)
            + "<table><tr><th>method</th><th>Mean/[mm]</th>"
            f"<th>Max/[mm]</th><th>Median/[mm]</th><th>SD/[mm]</th></tr>{rows}</table>"
            + img_tag(run, files.get("fig10"), "Fig. 10"))


def _sweep_section(run: Path, st: dict, files: dict) -> str:
    sw = st["sweep"]
    return (f"<h2>7. L1 / L2 sweep</h2><p>{sw['designs']} designs ({sw['ok']} valid); stiffest L1 = "
            f"{sw['stiffest']['L1_mm']:g} mm, L2 = {sw['stiffest']['L2_mm']:g} mm, c_rod "
            f"{sw['stiffest']['c_rod_um']:.0f} um.</p>" + img_tag(run, files.get("sweep"), "sweep heat maps"))


def _pct(share) -> str:
    return "—" if share is None or share != share else f"{100 * share:.0f}"


def _study_section(run: Path, sy: dict, files: dict, rod_note: str = "") -> str:
    """8. The study: predicted calibration accuracy of the paper's carbon rods per method."""
    rows = "".join(
        f"<tr><td>{html.escape(str(r['design']))}</td><td>{r['c_rod_um']:.0f}</td><td>{r['mass_kg'] * 1e3:.0f}</td>"
        f"<td>{html.escape(str(r['method']))}</td><td>{r['mean_mm']:.3f}</td><td>{r['mean_p05_mm']:.3f}-"
        f"{r['mean_p95_mm']:.3f}</td><td>{r['max_mm']:.3f}</td><td>{_pct(r['share_deflection'])} / "
        f"{_pct(r.get('share_slip'))} / {_pct(r['share_identification'])} / {_pct(r['share_noise'])}</td></tr>"
        for r in sy["rows"])
    return (f"<h2>8. Which rod? Predicted calibration accuracy (rodlab study)</h2><p><b>Recommendation.</b> "
            f"{html.escape(sy['recommendation'])}</p>{rod_note}<p class=note>{len(sy['designs'])} designs "
            f"({html.escape(', '.join(sy['designs']))}) on the TX90, "
            f"{html.escape(str(sy.get('predictor') or str(sy['replicates']) + ' simulated campaigns each'))} "
            f"(<code>rodlab study</code>; <code>--monte-carlo</code> simulates the campaigns); compliance: "
            f"{html.escape(sy['compliance'])} (the three rods differ only in L1 / L2, one family, so this is "
            "<code>rodlab study rod1 rod2 rod3 --robot tx90</code> with its defaults; the demo reuses the solid run "
            "of section 3 instead of making its own). "
            "Mean validation error after calibration, its 5-95 % band over the campaigns, and the error budget: the "
            "shares of the mean-square error from the rod's deflection left after compensation, its slip (the "
            "non-repeatable deflection no compensation removes), the identification "
            "and the validation instrument's noise. The whole study: <code>study/study.html</code>.</p>"
            "<table><tr><th>design</th><th>c_rod um</th><th>mass g</th><th>method</th><th>mean mm</th>"
            f"<th>90 % band mm</th><th>max mm</th><th>budget % (defl. / slip / ident. / noise)</th></tr>{rows}</table>"
            + img_tag(run, files.get("study_pareto"), "study Pareto fronts") + _study_views(run, files))


def _study_views(run: Path, files: dict) -> str:
    """The recommended design's frame centreline in 3-D under its weakest unit force (``rodlab study`` draws it
    beside ``recommended.vtp`` where pyvista renders), coloured by the sections' von Mises stress."""
    pngs = files.get("study_views") or []
    if not pngs:
        return ""
    return ("<p>The recommended design under the unit force that moves its ball most (frame model, displacement "
            "exaggerated, coloured by the sections' outer-fibre von Mises stress; all six load cases in "
            "<code>study/recommended.vtp</code>):</p>"
            + "".join(img_tag(run, p, f"3-D view {p}", _VIEW_SCALE) for p in pngs))


def _evidence(f: dict) -> str:
    from ..diagnose.report import Finding  # heavy: the diagnosis loads scipy.optimize, ~0.6 s
    from ..diagnose.wording import evidence_text  # heavy: the diagnosis loads scipy.optimize, ~0.6 s
    return evidence_text(Finding.from_dict(f))


def read_run(run: Path) -> dict:
    try:
        return json.loads((run / "run.json").read_text())
    except FileNotFoundError as e:
        raise RodlabError(f"{run}: no run.json here; run `rodlab demo -o {run}` first") from e


def _update_table(st) -> str:
    """The model update of the demo's diagnosis: each freed key, design -> as built +- sigma, and the truth."""
    up, truth = st["diagnose"].get("update"), st["rig"].get("as_built", {})
    if not up:
        return ""
    rows = "".join(f"<tr><td>{html.escape(k)}</td><td>{v0:.4g}</td><td>{v:.4g} &plusmn; {s:.2g}</td>"
                   f"<td>{truth.get(k, v0):.4g}</td></tr>"
                   for k, v0, v, s in zip(up["keys"], up["design"], up["as_built"], up["sigma"]))
    r = ", ".join(f"{a:.3f} -> {b:.3f}" for a, b in zip(up["r_before"], up["r_after"]))
    return ("<p><b>The rod as built</b> (<code>rodlab update</code> on the diagnosed linear compliance, written to "
            "<code>rod1.asbuilt.rod.toml</code>): r_mn (measured / frame model) " + html.escape(r) + ".</p>"
            "<table><tr><th>key</th><th>design</th><th>as built (fitted)</th><th>truth</th></tr>" + rows + "</table>")
