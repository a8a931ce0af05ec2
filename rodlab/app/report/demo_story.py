"""The demo page's story: the conclusion at the top (what to build, the accuracy to expect, with what
compensation), the terms where they first appear, and which rod each calibration section assumes.

Section 6 (the calibration) and section 8 (the study) assume different rods: section 6's simulated campaign
uses the rod as built of the rig sections (its FEA file changed by a softer laminate and a starved bond), section
8 rods as built with r_rod drawn from the material's prior (carbon 1.23-2.30). Both say so, and the conclusion joins them.
"""
from __future__ import annotations

import html

import numpy as np

from ...core.compliance import DEFAULT_CONTACT_FORCE_N

__all__ = ["conclusion_html", "terms_html", "campaign_rod_note", "study_rod_note"]

_LABEL = {"none": "None", "calc": "Calc", "fea": "FEA", "meas": "Meas"}
_BOX = "background:#f2f7f2;border:1px solid #9bc59b;padding:.3em 1em"


def _rows(sy: dict) -> dict:
    return {(str(r["design"]), str(r["method"])): r for r in sy.get("rows", [])}


def _prior(sy: dict, design: str) -> tuple[float, float]:
    from ..study.designs import R_PRIOR_COMPOSITE  # heavy: the study loads scipy.sparse (FEA), ~0.3 s
    return tuple(sy.get("r_prior", {}).get(design, R_PRIOR_COMPOSITE))


def _band(r: dict) -> str:
    return f"{r['mean_mm']:.3f} mm (90 % band {r['mean_p05_mm']:.3f}-{r['mean_p95_mm']:.3f} mm)"


def _table3_span(t3: dict) -> tuple[float, float]:
    means = [t3[k]["mean_mm"] for k in ("Calc", "FEA", "Meas") if k in t3]
    return min(means), max(means)


def _rod1_sentence(st: dict, rows: dict, sy: dict) -> str:
    """Rod 1# as built with a drawn r_rod (section 8) against the rig's rod as built (section 6)."""
    t3, name = st["calibrate"]["table3"], sy["designs"][0]
    lo, hi = _table3_span(t3)
    r_true = st.get("campaign", {}).get("r_rod_true")
    as_file = f"true r_rod = {r_true:.3f}" if r_true is not None else "r_rod ~ 1"
    built = ", ".join(f"{_LABEL[m]} {rows[(name, m)]['mean_mm']:.3f} mm" for m in ("meas", "calc", "fea", "none")
                      if (name, m) in rows)
    p = _prior(sy, name)
    return (f"<p><b>Rod {html.escape(name)}, the rod of sections 1-7</b>, as built (r_rod drawn from {p[0]:g}-{p[1]:g}): "
            f"predicted {built} (section 8). As the rig measured it ({as_file}, section 6) every "
            f"compensation reaches {lo:.3f}-{hi:.3f} mm (None {t3['None']['mean_mm']:.3f} mm). The two sections "
            "assume different rods, not different physics: only a measured compliance knows the rod as built.</p>")


def conclusion_html(st: dict) -> str:
    """What to build, the accuracy to expect and the compensation to use (from the study when it ran, else from
    the calibration of section 6)."""
    t3 = st["calibrate"]["table3"]
    if "study" not in st:
        lo, hi = _table3_span(t3)
        body = (f"<p>Rod 1# on the TX90: mean validation error {lo:.3f}-{hi:.3f} mm with the rod's deflection "
                f"compensated (Calc, FEA or Meas; section 6), {t3['None']['mean_mm']:.3f} mm without.</p>")
        return f"<h2>Conclusion</h2><div style='{_BOX}'>{body}</div>"
    sy = st["study"]
    rows, rec = _rows(sy), sy.get("recommended") or {}
    design, method = rec.get("design"), rec.get("method")
    if design is None or (design, method) not in rows:
        body = f"<p><b>Study:</b> {html.escape(sy['recommendation'])}</p>"
    else:
        r = rows[(design, method)]
        p = _prior(sy, design)
        others = ", ".join(f"{_LABEL[m]} {rows[(design, m)]['mean_mm']:.3f} mm" for m in ("calc", "fea", "none")
                           if (design, m) in rows and m != method)
        body = (f"<p><b>Build {html.escape(design)}</b> (L1 {rec['L1_mm']:g} mm, L2 {rec['L2_mm']:g} mm, "
                f"{r['mass_kg'] * 1e3:.0f} g). <b>Expect</b> a mean validation error of {_band(r)} on the TX90 "
                f"<b>with {_LABEL.get(method, method)} compensation</b>"
                + (": measure the rod on the stiffness rig (section 4) and calibrate with its measured compliance "
                   "file" if method == "meas" else "")
                + f". The rod as built is {p[0]:g}-{p[1]:g} x as compliant as simulated (this ratio is r_rod, the "
                f"correction factor, see Terms), so with a simulated compliance alone it gives {others} "
                "(section 8).</p>")
        body += _rod1_sentence(st, rows, sy)
    return f"<h2>Conclusion</h2><div style='{_BOX}'>{body}</div>"


def terms_html() -> str:
    """The page's terms, defined before any section uses them."""
    from ..study.designs import R_PRIOR_COMPOSITE, R_PRIOR_METAL  # heavy: the study loads scipy.sparse (FEA), ~0.3 s
    force = float(np.linalg.norm(DEFAULT_CONTACT_FORCE_N))
    rows = [
        ("{T}", "the rod's tool frame: origin at the ball centre, z_T along the flange normal (pipe I), x_T towards "
                "pipe II, y_T completing the right-handed frame (the axes of the CAD views)"),
        ("C_F, C_g", "the rod's compliance in {T}: the ball centre's displacement per force on the ball [um/N], and "
                     "under the rod's own weight per unit of gravity along each axis [um per g0]"),
        ("c_rod", f"compliance index (paper Eq. 23) [um]: sum of C_g's entries + sum of C_F's entries x the contact "
                  f"force {force:.2f} N; about how far gravity and the contact force move the ball. Smaller is stiffer"),
        ("r_rod", f"correction factor (paper Eq. 21): the real rod's compliance over the simulated one, (c22 + c33) "
                  f"measured / simulated; 1 when the model is exact. The paper measured {R_PRIOR_COMPOSITE[0]:g}-"
                  f"{R_PRIOR_COMPOSITE[1]:g} for carbon tubes, {R_PRIOR_METAL[0]:g}-{R_PRIOR_METAL[1]:g} for metal; "
                  "the stiffness rig measures it (section 4)"),
        ("None / Calc / FEA / Meas", "how the calibration compensates the rod's deflection: not at all, with the "
                                     "closed-form compliance, with the FEA compliance, with the compliance measured "
                                     "on the stiffness rig"),
    ]
    body = "".join(f"<tr><td class=l><b>{html.escape(k)}</b></td><td class=l>{html.escape(v)}</td></tr>"
                   for k, v in rows)
    return f"<h2>Terms</h2><table>{body}</table>"


def campaign_rod_note(st: dict) -> str:
    """Section 6: the campaign's rod is the rod as built of the rig sections (not its simulation)."""
    r_true = st.get("campaign", {}).get("r_rod_true")
    r = f" (true r_rod = {r_true:.3f})" if r_true is not None else ""
    return ("<p><b>Rod assumed: the rod as built of sections 4-5.</b> The simulated campaign's rod is rod 1#'s FEA "
            f"compliance changed by the laminate 7 % softer and the starved ring-1 bond of the rig recording{r}: "
            "the simulated compliances (Calc, FEA) miss it by that much, Meas and Corrected carry it. Section 8 "
            "predicts rods as built with r_rod drawn from the material's prior.</p>")


def study_rod_note(st: dict) -> str:
    """Section 8: each campaign's rod as built, its r_rod drawn from the material's prior."""
    sy = st["study"]
    rows, name = _rows(sy), sy["designs"][0]
    p = _prior(sy, name)
    t3 = st["calibrate"]["table3"]
    compare = ""
    if all((name, m) in rows for m in ("calc", "meas")) and "Calc" in t3:
        compare = (f" Rod {html.escape(name)} with Calc: {rows[(name, 'calc')]['mean_mm']:.3f} mm here against "
                   f"{t3['Calc']['mean_mm']:.3f} mm in section 6; with Meas {rows[(name, 'meas')]['mean_mm']:.3f} mm.")
    return ("<p><b>Rod assumed: as built.</b> In each simulated campaign the rod's true compliance is r_rod x its "
            f"simulated one (with a small shape error), r_rod drawn from {p[0]:g}-{p[1]:g} for these carbon tubes "
            "(the paper's measured range). Calc and FEA compensation leave that extra compliance in the calibration; "
            "Meas, measured on the real rod, does not." + compare + "</p>")
