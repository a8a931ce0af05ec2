"""A finding's evidence in an engineer's words: what it explains, how sure, and what would confirm it.

The statistics behind a finding (delta BIC, the likelihood-ratio test, cross-validated squared error) stay in
the diagnosis report for whoever wants them; what is printed and put in reports is

- the share of the residual's mean square the finding explains, with the rms before -> after in um;
- how sure: ``decisive`` when the likelihood-ratio p-value is below 1e-6 and cross-validation agrees,
  ``strong`` below 1e-3, otherwise ``weak``; the chance that noise alone made the improvement is stated;
- what would confirm it: a measurement or a change that should remove the finding (campaign findings reuse
  :func:`rodlab.app.diagnose.advice.remedy`).
"""
from __future__ import annotations

import math

from rodlab.core.enums import MODEL_FORM, FindingKind
from rodlab.stiffness_rig.effects import RIG_EFFECTS

from .report import Finding
from .rig_outside import confirm_outside
from .advice import remedy

__all__ = ["explained_share", "certainty", "caution", "confirmation", "evidence_text", "form_resolution"]

def _rig_confirm(effect: str, location: str | None = None) -> str | None:
    """What would confirm a rig finding: the effect module's sentence (:mod:`rodlab.stiffness_rig.effects`), or
    for physics outside the vocabulary :func:`.rig_outside.confirm_outside`."""
    if effect == FindingKind.UNEXPLAINED:
        return confirm_outside(location) or ("repeat the named steps: structure that returns is physics, structure "
                                             "that moves is handling; `--sim-accuracy exact` (the simulation taken "
                                             "as the rod) names what the tolerant diagnosis may leave to the rod's "
                                             "linear part")
    return next((m.confirm_for(location) for e, m in RIG_EFFECTS.items() if e.value == effect), None)


def explained_share(f: Finding) -> float:
    """Share of the residual's mean square the finding removes: ``1 - (rms_after / rms_before)^2``."""
    if not f.rms_before_mm > 0:
        return float("nan")
    return 1.0 - (f.rms_after_mm / f.rms_before_mm) ** 2


#: a likelihood ratio this improbable under noise is no chance fit, whatever a cross-validation says of it
OVERWHELMING_P = 1e-12


def certainty(f: Finding) -> str:
    """``decisive`` / ``strong`` / ``weak`` with the probability that noise alone explains the improvement."""
    p = f.evidence.get("lr_p")
    cv_ok = f.evidence.get("cv_sse_after", 0.0) < f.evidence.get("cv_sse_before", 1.0)
    if p is None or not math.isfinite(p):
        return "not tested" if f.effect != FindingKind.UNEXPLAINED else "the structure is significant; its cause is not modelled"
    chance = "below 1e-300" if p == 0 else f"{p:.1g}"
    if p < 1e-6 and cv_ok:
        level = "decisive"
    elif (p < 1e-3 and cv_ok) or p < OVERWHELMING_P:     # a creep at 3e-94 had been "weak" for its cross-validation
        level = "strong"
    else:
        level = "weak"
    cv = "" if cv_ok else (", though it does not predict held-out points better: another term may carry part of it"
                           if p < OVERWHELMING_P else ", and it does not predict held-out points better")
    return f"{level} (chance that noise alone gives this improvement: {chance}{cv})"


def caution(f: Finding) -> str | None:
    """The finding's caution: fitted parameters no rod or rig of its kind has (a units slip), or None."""
    return f.evidence.get("caution") or None


def confirmation(f: Finding) -> str:
    """What would confirm the finding (rig) or what to do about it (campaign)."""
    if f.effect == MODEL_FORM:
        return form_resolution(f)
    if f.evidence.get("separate_by"):
        return f"to tell the candidates apart: {f.evidence['separate_by']}"
    rig = _rig_confirm(f.effect, f.location)
    if rig and not (f.location or "").startswith(("position:", "points:", "joint:")):
        return rig
    return remedy(f)


def evidence_text(f: Finding) -> str:
    """One line: explains X % of the residual (rms a -> b um); how sure. A lack of fit (nothing fitted to it) says
    what is left instead."""
    if f.effect == MODEL_FORM:
        ev = f.evidence
        return (f"the linear compliance measured entry by entry takes the readings' rms against the simulation from "
                f"{f.rms_before_mm * 1e3:.2f} to {f.rms_after_mm * 1e3:.2f} um (what is left is the other findings' "
                f"and the noise); inside the envelope (chi-square {ev['envelope_chi2']:.2f} on {ev['envelope_dof']} "
                f"entries, p = {ev['envelope_p']:.2g}) of {ev.get('envelope', 'the simulation')}")
    if "readings_left_out" in f.parameters:          # readings screened out before the fit: not a fitted term
        return f"{f.parameters['readings_left_out']} readings left out before the diagnosis; nothing was fitted to them"
    if f.effect == FindingKind.UNEXPLAINED and "reduced_chi2" in f.parameters:   # the lack of fit: nothing fitted
        return (f"left after the findings: rms {f.rms_after_mm * 1e3:.2f} um; the structure is significant; its cause "
                "is not modelled")
    share = explained_share(f)
    if share < 0:          # it lowers the residual weighted by the noise model, not the plain rms
        return (f"raises the plain rms ({f.rms_before_mm * 1e3:.2f} -> {f.rms_after_mm * 1e3:.2f} um) while it lowers "
                f"the residual weighted by the noise model; {certainty(f)}")
    pct = "—" if share != share else f"{100 * share:.0f} %" if share < 0.995 else f"{100 * share:.1f} %"
    return (f"explains {pct} of the residual's mean square (rms {f.rms_before_mm * 1e3:.2f} -> "
            f"{f.rms_after_mm * 1e3:.2f} um); {certainty(f)}")


def form_resolution(f: Finding) -> str:
    """What would resolve a compliant joint inside a ``model_form`` envelope: the size that stands out now, the
    best fit, and the size a coupon test and a solid FEA would resolve; a direct measurement."""
    rows = f.evidence.get("resolve") or []
    if not rows:
        return ("a joint or a softer member of this size cannot be told from the tolerances; re-check against this "
                "measurement later (`rodlab diagnose --sim MEASURED.compliance.json --sim-accuracy exact`)")
    parts = []
    for r in rows:
        own = f.parameters.get(f"joints.{r['place']}.s_bend_rad_per_Nm")
        beside = (f"its bond in the as-built keys {own if abs(own) > 1e-12 else 0.0:.2g}, and beyond them "
                  if own is not None else "")
        txt = (f"{r['place']}: stands out above s_bend {r['detectable_s_bend_rad_per_Nm']:.2g} rad/(N m) ({beside}"
               f"a further {r['best_fit_s_bend_rad_per_Nm']:.2g} +- {r['sd_s_bend_rad_per_Nm']:.2g})")
        if "detectable_with_coupon_and_solid_fea" in r:
            txt += f", {r['detectable_with_coupon_and_solid_fea']:.2g} with a coupon test and a solid FEA"
        parts.append(txt)
    return ("a compliant joint inside this envelope is not located; " + "; ".join(parts) + ". A joint below these "
            "is resolved by dial gauges on each side of it (the angle jump) or by re-checking the rod against this "
            "measurement (`rodlab diagnose --sim MEASURED.compliance.json --sim-accuracy exact`)")
