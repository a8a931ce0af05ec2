"""One report section per result format: the registry ``rodlab report`` and every command's ``--report`` use.

A section renderer takes a :class:`Source` (the result's content and where it was written) and returns HTML;
``SECTIONS`` maps a format key to its title, place on the page and the figures it owns (file names that,
found beside the result, are shown in its section). Adding a format is one function and one registry entry.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from .html import esc, fmt, matrix_table, table

__all__ = ["Source", "Section", "SECTIONS", "FORMAT_SWEEP", "FORMAT_MASS", "FORMAT_COMPARISON"]

#: formats rodlab writes that carry no ``format`` key of their own (recognised by name / columns)
FORMAT_SWEEP = "rodlab.sweep/1"
FORMAT_MASS = "rodlab.mass/1"
FORMAT_COMPARISON = "rodlab.comparison/1"


@dataclass
class Source:
    """A result for a report.

    format : the contract format key (``rodlab.calibration/1`` ...); data : its content (a dict, or a pandas
    DataFrame for tables); path : the file it was written to, or None when rendered from memory.
    """

    format: str
    data: object
    path: Path | None = None

    def label(self, base: Path | None) -> str:
        """The file's path relative to ``base`` (the report's folder) when below it, else its name."""
        if self.path is None:
            return "(not written)"
        try:
            return str(self.path.resolve().relative_to(base.resolve())) if base else self.path.name
        except ValueError:
            return str(self.path)


@dataclass(frozen=True)
class Section:
    """title : heading; order : place on the page (design first, calibration last); render : Source -> HTML;
    figures : file names (or ``*`` suffix patterns) shown in this section when found beside the result."""

    title: str
    order: int
    render: Callable[[Source], str]
    figures: tuple = field(default_factory=tuple)


def _kv(rows: list[tuple[str, str]]) -> str:
    return table(["quantity", "value"], [list(r) for r in rows])


def _compliance(src: Source) -> str:
    d = src.data
    prov = d.get("provenance") or {}
    com = ", ".join(f"{round(v, 1) + 0.0:.1f}" for v in d["com_T_mm"])
    tool = ", ".join(f"{round(v, 1) + 0.0:.1f}" for v in d["tool_mm"])
    rows = [("rod / method", f"{d['rod']} / {d['method']}"),
            ("model", str(prov.get("model") or prov.get("generator") or "—")),
            ("r_rod (Eq. 21)", fmt(d.get("r_rod"), ".4f")), ("c_rod (Eq. 23)", f"{fmt(d.get('c_rod_um'), '.1f')} um"),
            ("mass", f"{d['mass_kg'] * 1e3:.1f} g"), ("centre of mass in {T}", f"{com} mm"),
            ("tool vector (flange to ball) in {6}", f"{tool} mm")]
    if prov.get("sparse_solver"):
        rows.append(("sparse solver", str(prov["sparse_solver"])))
    if d.get("r_mn"):
        cells = "; ".join(f"row {'xyz'[m]}: (" + ", ".join("n/m" if v is None else f"{v:.4f}" for v in row) + ")"
                          for m, row in enumerate(d["r_mn"]))
        rows.append(("r_mn (Eq. 20, measured / simulated per entry, columns x, y, z; n/m: not measured)", cells))
    load = prov.get("measured_load") or {}
    if load.get("friction_N"):
        rows.append(("slides' friction, measured by the load cell",
                     ", ".join(f"{a}: {v:+.3f} N" for a, v in load["friction_N"].items())))
    return (_kv(rows) + "<div class=grid><div><b>C_F</b>: ball displacement per tip force"
            + matrix_table(d["C_F_mm_per_N"], "um/N", "force") + "</div><div><b>C_g</b>: ball displacement under the "
            "rod's own weight per unit of gravity along each axis" + matrix_table(d["C_g_mm_per_g0"], "um per g0",
                                                                                 "gravity") + "</div></div>")


def _verdict(trusted: bool, warnings: list, cautions: list = ()) -> str:
    if trusted and cautions:
        items = "".join(f"<li>{esc(c)}</li>" for c in cautions)
        return f"<p class=good>TRUSTED, with cautions: the parameters may be loaded.</p><ul>{items}</ul>"
    if trusted:
        return "<p class=good>TRUSTED: the residuals are within the noise model; the parameters may be loaded.</p>"
    items = "".join(f"<li>{esc(w)}</li>" for w in warnings)
    items += "".join(f"<li>caution: {esc(c)}</li>" for c in cautions)
    return f"<p class=bad>NOT TRUSTED: do not load these parameters into the robot.</p><ul>{items}</ul>"


def _two_statements(fit: dict) -> str:
    """Usable? (the held-out accuracy against nominal) and complete? (the residual test), when recorded."""
    out = ""
    pr = fit.get("prediction")
    if pr and pr.get("points"):
        how = "validation" if pr["source"] == "validation" else f"{pr['folds']}-fold cross-validation"
        out += (f"<p>Usable? held-out mean error {fmt(pr['mean_mm'], '.3f')} mm against the nominal model's "
                f"{fmt(pr['nominal_mean_mm'], '.3f')} mm (difference {fmt(pr['gain_mm'], '.3f')} +- "
                f"{fmt(pr['gain_se_mm'], '.3f')} mm; {esc(how)} over {esc(pr['grouping'])}, {pr['points']} points)</p>")
    comp = fit.get("completeness")
    if comp:
        out += f"<p>{esc(comp['statement'][:1].upper() + comp['statement'][1:])}</p>"
    return out


def _stats_rows(validation: dict) -> list[list]:
    return [[k, fmt(v["mean_mm"], ".3f"), fmt(v["max_mm"], ".3f"), fmt(v["median_mm"], ".3f"), fmt(v["sd_mm"], ".3f"),
             v.get("points", "—")] for k, v in validation.items()]


def _socket_checks(sockets: dict) -> str:
    """``--sockets``: each model's consistency and distortion on the fitted and the held-out placements."""
    rows = [[label, model, ", ".join(map(str, c["placements"])), c["readings"], fmt(c["spread_mean_mm"], ".3f"),
             fmt(c["spread_max_mm"], ".3f"), fmt(c["distance_rms_mm"], ".3f"), fmt(c["distance_max_mm"], ".3f")]
            for label, pair in sockets.get("checks", {}).items() for model, c in pair.items()]
    return ("<h3>Consistency and distortion (socket readings)</h3><p class=note>spread: distance of each ball "
            "position from its socket's centre, located from that model's ball positions alone; distance: the model's "
            "socket distance minus the stated one. Held-out placements were not used by the fit.</p>"
            + table(["readings", "model", "placements", "readings n", "spread mean mm", "spread max mm",
                     "distance rms mm", "distance max mm"], rows))


def _calibration(src: Source) -> str:
    d = src.data
    fit = d.get("fit", {})
    parts = [_verdict(bool(d.get("trusted")), fit.get("warnings", []), fit.get("cautions", [])) + _two_statements(fit),
             _kv([("robot", d["robot"]), ("compensation", str(d["compensation"])), ("points", str(d["points"])),
                  ("residual rms", f"{d['residual_rms_mm'] * 1e3:.2f} um"),
                  ("condition number", fmt(fit.get("condition"), ".3g")),
                  ("solver", f"{fit.get('message', '—')} ({fit.get('nfev', '—')} evaluations)")])]
    if d.get("validation"):
        parts.append("<h3>Validation (positioning error at independent points)</h3>"
                     + table(["model", "mean mm", "max mm", "median mm", "SD mm", "points"],
                             _stats_rows({{"before": "nominal", "after": "calibrated"}.get(k, k): v
                                          for k, v in d["validation"].items()})))
    if d.get("sockets"):
        parts.append(_socket_checks(d["sockets"]))
    rows = [[k, fmt(p["value"], ".6g"), fmt(p.get("sigma"), ".3g"), p.get("unit", ""), p.get("status", "")]
            for k, p in d["parameters"].items() if p.get("status") != "fixed"]
    fixed = [f"{k} = {p['value']:g} {p.get('unit', '')}" for k, p in d["parameters"].items()
             if p.get("status") == "fixed"]
    parts.append("<h3>Parameters</h3><p class=note>sigma: one standard deviation from the fit; regularised: held "
                 "near its prior because the campaign hardly sees it.</p>"
                 + table(["parameter", "value", "sigma", "unit", "status"], rows))
    if d.get("joint_harmonics"):
        spans = ", ".join(f"joint {j}: {v['q_min_deg']:.1f}..{v['q_max_deg']:.1f} deg"
                          for j, v in d["joint_harmonics"].items())
        parts.append("<p class=note>h1s_j .. h2c_j: the periodic error of joint j's reading, theta_j = q_j + ... + "
                     "h (f(q_j) - its mean over the calibration's readings), f = sin q, cos q, sin 2q, cos 2q; "
                     f"identified over the readings {esc(spans)}: not to be used outside that range.</p>")
    if fixed:
        parts.append(f"<p class=note>Held at their nominal values ({len(fixed)}): " + esc(", ".join(fixed)) + ".</p>")
    if d.get("unidentifiable"):
        parts.append("<details><summary>Why they are held</summary><ul>"
                     + "".join(f"<li>{esc(u)}</li>" for u in d["unidentifiable"]) + "</ul></details>")
    return "".join(parts)


def _finding_rows(findings: list, subject: str) -> list[list]:
    from ..diagnose.report import Finding  # heavy: the diagnosis loads scipy.optimize, ~0.6 s
    from ..diagnose.wording import caution, confirmation, evidence_text  # heavy: the diagnosis loads scipy.optimize, ~0.6 s
    rows = []
    for f in findings:
        fi = Finding.from_dict(f)
        params = ", ".join(f"{k} = {v:.4g}" + (f" [{fi.intervals[k][0]:.3g}, {fi.intervals[k][1]:.3g}]"
                                                if k in fi.intervals else "")
                           for k, v in fi.parameters.items() if isinstance(v, (int, float)))
        rows.append([f["effect"] + (f" at {f['location']}" if f["location"] else ""), params or "—",
                     evidence_text(fi), fi.explanation,
                     (f"caution: {caution(fi)}; " if caution(fi) else "") + confirmation(fi)])
    return rows


def _diagnosis(src: Source) -> str:
    d = src.data
    subject = d["subject"]
    parts = [f"<p>Verdict <b>{esc(d['verdict'])}</b> ({esc(subject)}): noise {d['noise_mm'] * 1e3:.2f} um per "
             f"reading; rms of the residuals {d['rms_before_mm'] * 1e3:.2f} -> {d['rms_after_mm'] * 1e3:.2f} um with "
             "the findings modelled.</p>"]
    if d["findings"]:
        parts.append(table(["finding", "fitted parameters [95 % interval]", "what it explains, how sure", "physics",
                            "to confirm" if subject == "rig" else "next step"],
                           _finding_rows(d["findings"], subject), left=5))
    else:
        parts.append("<p>No finding: the recording is explained by the simulated model and the noise.</p>")
    if d.get("validation"):
        names = {"nominal": "nominal", "before": "calibrated as given", "after": "with the found physics"}
        v = {names.get(k, k): s for k, s in d["validation"].items()}
        parts.append("<h3>Validation</h3>" + table(["model", "mean mm", "max mm", "median mm", "SD mm", "points"],
                                                   _stats_rows(v)))
    return "".join(parts)


def _points_diagnosis(src: Source) -> str:
    d = src.data
    verdict = "consistent with the instrument's noise" if d["consistent"] else "NOT explained by the noise"
    parts = [f"<p>{d['points']} poses: residual rms {d['residual_rms_mm'] * 1e3:.1f} um per coordinate against "
             f"{d['noise_mm'] * 1e3:.1f} um of instrument noise (reduced chi-square {d['reduced_chi2']:.1f}): "
             f"<b>{esc(verdict)}</b>.</p>"]
    if d["findings"]:
        parts.append(table(["finding", "where", "share of the residual", "p", "meaning"],
                           [[f["effect"], f["where"], f"{f['explained_share']:.0%}", f"{f['p_value']:.1e}",
                             f["meaning"]] for f in d["findings"]], left=5))
    if d["regions"]:
        parts.append("<h3>Workspace regions</h3>" + table(
            ["region", "poses", "rms um"], [[r["region"], r["points"], f"{r['rms_mm'] * 1e3:.0f}"]
                                            for r in d["regions"]], left=1))
    return "".join(parts)


def _comparison(src: Source) -> str:
    d = src.data
    rows = [[k, fmt(v["mean_mm"], ".3f"), fmt(v["max_mm"], ".3f"), fmt(v["median_mm"], ".3f"), fmt(v["sd_mm"], ".3f"),
             fmt(v.get("fit_rms_um"), ".2f"), {True: "yes", False: "NO"}.get(v.get("trusted"), "—")]
            for k, v in d["methods"].items()]
    return (f"<p>{esc(d['robot'])}, campaign <code>{esc(d.get('campaign', ''))}</code>; the paper's Table 3 for this "
            "campaign: validation error after calibrating with each compensation method.</p>"
            + table(["method", "Mean mm", "Max mm", "Median mm", "SD mm", "fit rms um", "trusted"], rows))


def _study(src: Source) -> str:
    d = src.data
    rec = d.get("recommendation") or {}
    parts = [f"<p><b>Recommendation.</b> {esc(rec.get('text', '—'))}</p>",
             f"<p class=note>{esc(d.get('designs'))} designs on {esc(d.get('robot'))}; compliance: "
             f"{esc(d.get('compliance', '—'))}. The full study page is <code>study.html</code> beside this file.</p>"]
    csv = src.path.parent / "study.csv" if src.path else None
    if csv is not None and csv.exists():
        import pandas as pd
        df = pd.read_csv(csv)
        ok = df[df["method"].notna()].sort_values("mean_mm").head(20)
        rows = [[r.design, r.method, fmt(r.mean_mm, ".3f"), f"{fmt(r.mean_p05_mm, '.3f')}-{fmt(r.mean_p95_mm, '.3f')}",
                 fmt(r.max_mm, ".3f"), fmt(r.c_rod_um, ".0f"), fmt(r.mass_kg * 1e3, ".0f")] for r in ok.itertuples()]
        parts.append("<h3>The 20 most accurate (design, method) pairs</h3>"
                     + table(["design", "method", "mean mm", "90 % band mm", "max mm", "c_rod um", "mass g"], rows, 2))
    return "".join(parts)


def _sweep(src: Source) -> str:
    df = src.data
    ok = df[df["status"] == "ok"]
    parts = [f"<p>{len(df)} designs, {len(ok)} valid.</p>"]
    if len(ok):
        stiff, light = ok.loc[ok["c_rod_um"].idxmin()], ok.loc[ok["mass_kg"].idxmin()]
        parts.append(_kv([("stiffest", f"L1 = {stiff['L1_mm']:g} mm, L2 = {stiff['L2_mm']:g} mm: c_rod "
                                       f"{stiff['c_rod_um']:.0f} um, {stiff['mass_kg'] * 1e3:.0f} g"),
                          ("lightest", f"L1 = {light['L1_mm']:g} mm, L2 = {light['L2_mm']:g} mm: c_rod "
                                       f"{light['c_rod_um']:.0f} um, {light['mass_kg'] * 1e3:.0f} g")]))
    bad = df[df["status"] != "ok"]
    if len(bad):
        parts.append(table(["L1 mm", "L2 mm", "status", "why"],
                           [[f"{r.L1_mm:g}", f"{r.L2_mm:g}", r.status, r.message] for r in bad.head(20).itertuples()],
                           left=4))
    return "".join(parts)


def _mass(src: Source) -> str:
    d = src.data
    def com(v):
        return ", ".join(f"{round(c, 1) + 0.0:.1f}" for c in v["com_T_mm"])
    rows = [[p, v.get("material", "—"), f"{v['mass_kg'] * 1e3:.1f}", com(v)] for p, v in d["parts"].items()]
    t = d["total"]
    rows.append(["total", "", f"{t['mass_kg'] * 1e3:.1f}", com(t)])
    return (f"<p>Rod {esc(d.get('rod', '—'))}; frame: {esc(d.get('frame', 'T'))}.</p>"
            + table(["part", "material", "mass g", "centre of mass in {T} [mm]"], rows, 2))


def _joints(src: Source) -> str:
    d = src.data
    margins = ", ".join(f"{m:g}" for m in d.get("margins_mm", []))
    return _kv([("calibrated on", str(d["design"].get("name", "—"))), ("tube margins [mm]", margins or "—"),
                ("frame revision", str(d.get("frame_revision", "—"))),
                ("span residual", fmt(d.get("span_residual"), ".3g"))])


#: format key -> its section
SECTIONS: dict[str, Section] = {
    FORMAT_MASS: Section("Rod CAD: parts and mass", 10, _mass, ("view_iso.png", "view_xz.png", "view_xy.png",
                                                               "view_yz.png")),
    "rodlab.compliance/1": Section("Compliance file", 20, _compliance, ("deformed.png", "fig8.png")),
    "rodlab.compliance/2": Section("Compliance file", 20, _compliance, ("deformed.png", "fig8.png")),
    "rodlab.joints/1": Section("Joint calibration of the beam frame", 25, _joints),
    FORMAT_SWEEP: Section("L1 x L2 sweep", 30, _sweep, ("*sweep.png",)),
    "rodlab.study/1": Section("Design study: predicted calibration accuracy", 40, _study, ("pareto.png", "heatmaps.png")),
    "rodlab.diagnosis/1": Section("Diagnosis", 60, _diagnosis, ("diagnosis_rig.png", "diagnosis_campaign.png",
                                                                 "error_distributions.png")),
    "rodlab.points_diagnosis/1": Section("Diagnosis of instrument points", 61, _points_diagnosis),
    "rodlab.calibration/1": Section("Calibration", 50, _calibration, ("residuals.png", "error_distributions.png")),
    "rodlab.calibration/2": Section("Calibration", 50, _calibration, ("residuals.png", "error_distributions.png")),
    FORMAT_COMPARISON: Section("Compensation methods compared (Table 3)", 55, _comparison, ("*fig10.png",)),
}
