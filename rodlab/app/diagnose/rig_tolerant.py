"""A rig diagnosis that holds when the simulation is off in form (the rod as built is never its simulation).

1. The linear compliance the recording measures (the structural C_F entries, :mod:`.rig_linear`) is a free
   nuisance of the reading model beside each series' gauge zero; every hypothesis that no linear compliance can
   produce (friction, tare, creep, hysteresis, non-linearity, crosstalk, drift, the gauge non-linearity outside
   the vocabulary) is built on the freely fitted compliance and selected as in the exact diagnosis, against the
   residual with the linear part projected out.
2. The fitted linear part, with its covariance, is judged against the simulation's envelope (:mod:`.rig_form`):
   ``model_form`` inside it; a compliant joint, torsion or a uniform scale only outside it.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import MODEL_FORM, Subject, Verdict
from rodlab.stiffness_rig.effects import RIG_EFFECTS, HypothesisContext, joint_places
from rodlab.stiffness_rig.samples import RigSamples

from .envelope import Envelope
from .report import Diagnosis
from .rig_form import judge_linear
from .rig_linear import Projector, fit_linear, linear_columns, measured_entries
from .rig_outside import OUTSIDE, outside_hypotheses
from .rig_select import demean, subset_ls
from .rig_steps import Prep, RigModelFit, lack_of_fit, select_refining_creep, term_findings

__all__ = ["diagnose_tolerant", "verdict_of"]


def _hypotheses(data: RigSamples, C: np.ndarray, places: dict, tool: np.ndarray, structural: bool) -> list:
    """The structural effects' hypotheses (linear compliance changes) or the others, built on compliance ``C``."""
    ctx = HypothesisContext(np.asarray(C, float), C[data.comp, data.axis] * data.F, places, tool)
    return [h for m in RIG_EFFECTS.values() if m.structural == structural for h in m.hypotheses(data, ctx)]


def diagnose_tolerant(data: RigSamples, sim: RodCompliance, design, max_terms: int, env: Envelope,
                      sigma: float, scatter: float = 1.0, floor_mm: float | None = None
                      ) -> tuple[Diagnosis, RigModelFit]:
    """Diagnose ``data`` against ``sim`` within the envelope ``env`` (the steps of the module docstring); ``sigma``
    the noise of one reading [mm] (:func:`.rig_noise.reading_noise`); ``scatter``: the hold means' reduced
    chi-square that no effect explains (>= 1): effects are selected against ``sigma * sqrt(scatter)``, the hold
    means' lack of fit against ``sigma``; ``floor_mm``: the change a term must make to be seen (default
    ``sigma``; :func:`.rig_noise.detection_floor_mm`)."""
    n = data.y.size
    sigma_sel = sigma * float(np.sqrt(max(scatter, 1.0)))
    groups = data.zero_groups
    entries = measured_entries(data, sim.C_F)
    L = linear_columns(data, entries)
    prep = Prep(groups, Projector(groups, L), sigma if floor_mm is None else floor_mm)
    lin0 = fit_linear(data, entries, L, data.y, sigma, sim.C_F)
    places, tool = joint_places(sim.tool_mm, design), np.asarray(sim.tool_mm, float)
    base = lin0.C_F[data.comp, data.axis] * data.F
    r_sim = demean(data.y - sim.C_F[data.comp, data.axis] * data.F, groups)
    r0 = prep.project(data.y)
    vocabulary = _hypotheses(data, lin0.C_F, places, tool, False)
    nuisance = [h.X for h in vocabulary if not h.dC]
    library = [prep(t) for t in vocabulary + outside_hypotheses(data, base, np.column_stack(nuisance) if nuisance
                                                                else None)]
    folds = data.repeat if np.unique(data.repeat).size >= 2 else None
    library, ls, S = select_refining_creep(library, subset_ls(library, r0, folds), data, base, r0, prep, sigma_sel,
                                           max_terms, folds)
    coef, rss = ls.fit(S)
    library, ls, coef, rss = _on_refined_linear(library, ls, S, coef, rss, _Refit(data, entries, L, prep, sigma, sim,
                                                                                   places, tool, r0, folds))
    chosen = [library[j] for j in S]
    findings = term_findings(library, ls, S, coef, rss, sigma_sel, float(r0 @ r0))
    resid = ls.residual(S, coef)
    lack = lack_of_fit(data, resid, sigma, lin0.C_F)
    linear = fit_linear(data, entries, L, data.y - prep.fitted_change(chosen, coef), sigma, sim.C_F, lack.chi_red,
                        prep.raw_columns(chosen))
    rms_sim, rms_lin, rms = (float(np.sqrt(v / n)) for v in (r_sim @ r_sim, r0 @ r0, rss))
    judged = None
    if entries:
        causes = _hypotheses(data, np.asarray(sim.C_F, float), places, tool, True)
        judged = judge_linear(linear, env, causes, (rms_sim, rms_lin))
        findings += judged.findings
    verdict = verdict_of(findings)
    for finding in lack.findings(rms, sigma):
        findings.append(finding)
        verdict = Verdict.UNEXPLAINED
    model = RigModelFit(chosen, coef, resid, r_sim, data, sigma, lack.hold_z2(), lack.hold_offset_mm(), linear)
    extra = {"reduced_chi2_hold_means": lack.chi_red, "simulation_accuracy": str(env.kind),
             "envelope": env.source, "linear_part": _linear_dict(linear, sim)}
    if judged is not None:
        extra["linear_part"].update(judged.to_dict())
    return Diagnosis(Subject.RIG, verdict, sigma, rms_sim, rms, findings, extra), model


@dataclass(frozen=True)
class _Refit:
    """What rebuilding the chosen terms on a refined linear compliance needs (:func:`_on_refined_linear`)."""

    data: RigSamples
    entries: list
    L: np.ndarray
    prep: Prep
    sigma: float
    sim: RodCompliance
    places: dict
    tool: np.ndarray
    r0: np.ndarray
    folds: np.ndarray | None


def _term_key(h) -> tuple:
    """A hypothesis's identity across rebuilds: effect, place, settings and its physics (an effect's variants, such
    as friction that lets go at mass 0 or not, differ in that alone)."""
    return h.effect, h.location, tuple(sorted(h.settings.items())), h.explanation


def _on_refined_linear(library, ls, S: tuple, coef, rss: float, rf: _Refit, passes: int = 2):
    """The chosen vocabulary terms rebuilt on the linear compliance fitted beside them, and refitted. The terms are
    built on the compliance fitted freely before any of them, which a tare or friction biases (the loaded holds
    off the unloaded ones: a technician trial, tare 0.111 kg [0.110, 0.113] for 0.120, friction 5 % high): each
    pass refits the linear part to the readings less the chosen terms' change, rebuilds those terms on it (the
    same effect, place, settings and physics) and refits their coefficients; the selection stands. A term with no
    such twin (a creep whose time constant was refined off the grid, a term outside the vocabulary) keeps the
    columns it was selected with. Returns (library, its :class:`SubsetLS`, coef, rss)."""
    for _ in range(passes):
        chosen = [library[j] for j in S]
        lin = fit_linear(rf.data, rf.entries, rf.L, rf.data.y - rf.prep.fitted_change(chosen, coef), rf.sigma,
                         rf.sim.C_F)
        fresh = {_term_key(h): h for h in _hypotheses(rf.data, lin.C_F, rf.places, rf.tool, False)}
        swap = {j: replace(fresh[_term_key(library[j])], profile=library[j].profile)
                for j in S if _term_key(library[j]) in fresh}        # a creep keeps its time constant's profile
        if not swap:
            break
        library = [rf.prep(swap[j]) if j in swap else t for j, t in enumerate(library)]
        ls = subset_ls(library, rf.r0, rf.folds)
        coef, rss = ls.fit(S)
    return library, ls, coef, rss


def verdict_of(findings: list) -> Verdict:
    """``model_form`` alone is nothing left out (consistent); any cause explains; ``unexplained`` wins."""
    if any(f.effect == OUTSIDE for f in findings):
        return Verdict.UNEXPLAINED
    return Verdict.EXPLAINED if any(f.effect != MODEL_FORM for f in findings) else Verdict.CONSISTENT


def _linear_dict(linear, sim: RodCompliance) -> dict:
    """The measured linear compliance for the report: entries, values, standard deviations, r_mn."""
    return {"entries": [f"c{m + 1}{n + 1}" for m, n in linear.entries],
            "C_F_mm_per_N": [float(c) for c in linear.C], "sd_mm_per_N": [float(s) for s in linear.sd()],
            "r_mn": [float(c / sim.C_F[m, n]) for (m, n), c in zip(linear.entries, linear.C)]}
