"""Diagnosis of a stiffness-rig recording against the simulated compliance of its rod.

1. Screen: the noise of one reading from the within-hold scatter (detrended per hold; never from a model
   fit); the simulated model's residuals.
2. Attribute: a beam search over subsets of the hypothesis library (every rig effect's
   hypotheses, :mod:`rodlab.stiffness_rig.effects`), each term fitted
   with physical bounds (:mod:`.rig_select`, :mod:`.subset`). A larger model replaces the current one only
   if delta BIC <= -10 (known noise), the likelihood-ratio test gives p < 1e-3 and the leave-one-repeat-out
   prediction error drops; every term must change the readings of a series by >= 1 noise SD peak to peak and
   stay off its physical bounds, and must pass a drop-one test in the final model; at most ``max_terms``.
3. Locate: joint springs at the candidate places compete; when the runner-up fits within delta BIC 10 the
   finding names the group and the measurement that would separate them.
4. Explain: parameters with 95 % intervals, a sentence of physics; structure left above the noise (reduced
   chi-square of the hold means) makes the verdict ``unexplained`` with where it is. One hold far off all
   the others (a bumped gauge, a mislabelled load) is left out and named, not explained away.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from ...compliance import RodCompliance
from rodlab.stiffness_rig.effects import HypothesisContext, creep_hypothesis, joint_places, rig_hypotheses
from rodlab.stiffness_rig.samples import RigSamples, rig_samples

from .criteria import DBIC_MIN, bic_penalty, evidence
from .report import Diagnosis, Finding
from .rig_outside import OUTSIDE, outside_hypotheses
from .rig_select import alternatives, compatible, demean, refine_tau, select, subset_ls

__all__ = ["diagnose_rig", "RigModelFit", "joint_places"]

log = logging.getLogger(__name__)



@dataclass
class RigModelFit:
    """The model a rig diagnosis chose, for export and figures.

    terms : the chosen hypotheses (:class:`~rodlab.hypothesis.Hypothesis`); coef : their fitted internal
    parameters, concatenated in ``terms`` order; resid : residual of every sample after the fit [mm];
    base_resid : residual against the simulated compliance alone (gauge zeros removed) [mm]; data : the samples
    (:class:`~rodlab.stiffness_rig.samples.RigSamples`); sigma : noise of one reading [mm]; hold_z2 : {step: sum of
    squared z-scores of its hold means}; hold_offset_mm : {step: largest hold-mean residual [mm]}
    """

    terms: list
    coef: np.ndarray
    resid: np.ndarray
    base_resid: np.ndarray
    data: RigSamples
    sigma: float
    hold_z2: dict
    hold_offset_mm: dict

    def term_values(self):
        """(hypothesis, its fitted internal parameters) of every chosen term."""
        k = 0
        for term in self.terms:
            yield term, self.coef[k:k + term.X.shape[1]]
            k += term.X.shape[1]


def within_hold_noise(data: RigSamples) -> float:
    """Pooled SD of readings about a straight line in time within each (hold, component)."""
    ss, dof = 0.0, 0
    keys = data.step * 4 + data.comp
    for k in np.unique(keys):
        m = keys == k
        if m.sum() < 4:
            continue
        t, y = data.t_hold[m], data.y[m]
        A = np.column_stack([np.ones_like(t), t - t.mean()])
        coef, *_ = np.linalg.lstsq(A, y, rcond=None)
        ss += float(((y - A @ coef) ** 2).sum())
        dof += m.sum() - 2
    return float(np.sqrt(ss / max(dof, 1)))


def diagnose_rig(rec, sim: RodCompliance, design=None, max_terms: int = 3) -> tuple[Diagnosis, RigModelFit]:
    """Diagnose ``rec`` against ``sim``; returns the report and the fitted model (for export and figures).

    A single hold far off all the others (a bumped gauge, a mislabelled load) is not physics of the rod or
    the rig: when one hold carries most of the lack of fit and leaving it out removes the lack of fit, the
    diagnosis is of the recording without it, and an ``unexplained`` finding names the hold.
    """
    data = rig_samples(rec)
    diag, model = _diagnose(data, sim, design, max_terms)
    if not _lacks_fit(diag):
        return diag, model
    z2 = model.hold_z2
    steps = np.array(sorted(z2))
    tot = np.array([z2[k] for k in steps])
    w = int(steps[np.argmax(tot)])
    if tot.max() < 100.0 or tot.max() < 0.5 * tot.sum():
        return diag, model
    keep = data.step != w
    diag2, model2 = _diagnose(data.subset(keep), sim, design, max_terms)
    if _lacks_fit(diag2):
        return diag, model
    off = model.hold_offset_mm[w]
    diag2.findings.append(Finding(
        "unexplained", f"step:{w}", f"one hold is off all the others by {off * 1e3:.1f} um (largest component), "
        "which no effect of the rod or the rig produces (a bumped gauge or a mislabelled load); it was left out "
        "and the rest diagnosed without it", {"hold_offset_mm": off}, {}, diag2.rms_after_mm, diag2.rms_after_mm,
        {"hold_chi2": float(tot.max()), "share_of_lack_of_fit": float(tot.max() / tot.sum())}))
    diag2.verdict = "unexplained"
    diag2.extra["excluded_steps"] = [w]
    return diag2, model2


def _lacks_fit(diag: Diagnosis) -> bool:
    """Structure is left that nothing modelled explains (a physics outside the vocabulary that *was* modelled,
    such as a gauge's non-linearity, is not lack of fit)."""
    return any(f.effect == OUTSIDE and not f.evidence.get("outside_vocabulary") for f in diag.findings)


def _diagnose(data: RigSamples, sim: RodCompliance, design, max_terms: int) -> tuple[Diagnosis, RigModelFit]:
    """Screen, attribute, locate and explain one recording (the steps of the module docstring)."""
    sigma = within_hold_noise(data)
    n = data.y.size
    base = sim.C_F[data.comp, data.axis] * data.F
    # the zero of each gauge in each series is a nuisance parameter (it was set on one noisy, quantised
    # reading): project it out of the residual and of every term's columns (Frisch-Waugh)
    groups = data.axis * 4 + data.comp
    r0 = demean(data.y - base, groups)
    library = rig_hypotheses(data, HypothesisContext(np.asarray(sim.C_F, float), base,
                                                     joint_places(sim.tool_mm, design), np.asarray(sim.tool_mm, float)))
    library += outside_hypotheses(data, base)
    for t in library:
        t.X = demean(t.X, groups)
    folds = data.repeat if np.unique(data.repeat).size >= 2 else None
    library, ls, S = _select_refining_creep(library, subset_ls(library, r0, folds), data, base, r0, groups,
                                            sigma, max_terms, folds)
    coef, rss = ls.fit(S)
    findings = _findings(library, ls, S, coef, rss, sigma, float(r0 @ r0))
    resid = ls.residual(S, coef)
    rms = float(np.sqrt(rss / n))
    lack = _lack_of_fit(data, resid, sigma)
    verdict = "consistent" if not findings else "unexplained" if any(f.effect == OUTSIDE for f in findings) \
        else "explained"
    for finding in lack.findings(rms, sigma):
        findings.append(finding)
        verdict = "unexplained"
    model = RigModelFit([library[j] for j in S], coef, resid, r0, data, sigma, lack.hold_z2(), lack.hold_offset_mm())
    return Diagnosis("rig", verdict, sigma, float(np.sqrt(r0 @ r0 / n)), rms, findings,
                     {"reduced_chi2_hold_means": lack.chi_red}), model


def _select_refining_creep(library, ls, data: RigSamples, base, r0, groups, sigma: float, max_terms: int, folds):
    """Select a model; creep's time constant was picked from a grid: refine it continuously in the chosen model
    and in each of its sub-models that keep creep, then select again among the refined ones (a grid mismatch
    at high SNR must not be patched with extra terms such as a compliance scale). Returns (library, its
    :class:`SubsetLS`, the chosen term indices)."""
    S = select(library, ls, sigma, r0.size, max_terms, groups)
    for _ in range(2):
        creep = [j for j in S if library[j].effect == "creep"]
        if not creep:
            break
        j = creep[0]
        taus = []
        for sub in [S] + [tuple(i for i in S if i != k) for k in S if k != j]:
            tau = refine_tau(library, sub, j, data, base, r0, groups)
            if all(abs(np.log(tau / t)) > 0.01 for t in taus):
                taus.append(tau)
        if all(abs(np.log(t / library[j].settings["tau_s"])) < 0.01 for t in taus):
            break
        refined = []
        for tau in taus:
            refined.append(creep_hypothesis(data, base, tau))
            refined[-1].X = demean(refined[-1].X, groups)
        library = [t for t in library if t.effect != "creep"] + refined
        ls = subset_ls(library, r0, folds)
        S = select(library, ls, sigma, r0.size, max_terms, groups)
    return library, ls, S


def _findings(library, ls, S: tuple, coef, rss: float, sigma: float, rss0: float) -> list[Finding]:
    """One finding per chosen term, in the order the terms explain the residual: parameters with 95 %
    intervals, the drop-one likelihood ratio as evidence, the places and effects the data cannot tell apart."""
    n = ls.r.size
    cv_full = ls.cv_error(S)
    # strength of each term: the likelihood ratio of dropping it from the final model
    drop = {}
    for j in S:
        rest = tuple(i for i in S if i != j)
        _, rss_r = ls.fit(rest)
        drop[j] = ((rss_r - rss) / sigma ** 2, ls.cv_error(rest))
    cols = ls.columns(S)
    Gn = ls.G[np.ix_(cols, cols)] * np.outer(ls.norms[cols], ls.norms[cols])
    se_all = np.sqrt(np.clip(np.diag(sigma ** 2 * np.linalg.pinv(Gn)), 0, None))
    offsets = dict(zip(S, np.cumsum([0] + [library[j].X.shape[1] for j in S])[:-1]))
    findings = []
    rss_prev = rss0
    order = _explaining_order(ls, S)
    for m, j in enumerate(order):
        term = library[j]
        kj = term.X.shape[1]
        val, se = coef[offsets[j]:offsets[j] + kj], se_all[offsets[j]:offsets[j] + kj]
        _, rss_m = ls.fit(tuple(sorted(order[:m + 1])))
        ev = dict(evidence(drop[j][0], term.n_params, bic_penalty(term.n_params, n)).to_dict(),
                  cv_sse_before=float(drop[j][1]), cv_sse_after=float(cv_full))
        location = term.location
        places = _other_places(library, ls, S, j, rss, sigma) if term.effect == "joint_compliance" else []
        if places:
            location = "|".join([term.location] + places)
            ev["separate_by"] = ("load along x_T with the x gauge (pipe I bending) and along y_T (torsion): "
                                       "the lever from each place to the ball differs in each")
        alts_j = alternatives(library, ls, S, j, rss, sigma, n)
        if alts_j:
            ev["alternatives"] = alts_j
        if term.effect == OUTSIDE:
            ev["outside_vocabulary"] = True
        params, intervals = term.reported(val, se)
        findings.append(Finding(term.effect, location, term.explanation, params, intervals,
                                float(np.sqrt(rss_prev / n)), float(np.sqrt(rss_m / n)), ev))
        rss_prev = rss_m
    return findings


def _other_places(library, ls, S: tuple, j: int, rss: float, sigma: float) -> list[str]:
    """Ambiguity among places: the other joint-spring places that, put in place of term ``j``, fit within
    delta BIC 10."""
    alts = []
    for i, u in enumerate(library):
        if u.effect == "joint_compliance" and i != j:
            alt = tuple(sorted([x for x in S if x != j] + [i]))
            if len(set(alt)) == len(alt) and all(compatible(library, tuple(x for x in alt if x != y), y)
                                                 for y in alt):
                if (ls.fit(alt)[1] - rss) / sigma ** 2 < DBIC_MIN:
                    alts.append(u.location)
    return alts


@dataclass
class _LackOfFit:
    """The hold means' residuals after the chosen model: structure the library does not explain.

    keys : shape=(m,) the (hold, component) keys ``step * 4 + comp``; mean_r : shape=(m,) mean residual of each
    [mm]; z : shape=(m,) its z-score; chi_red : mean z^2; rho : pooled lag-1 autocorrelation within the holds
    """

    keys: np.ndarray
    mean_r: np.ndarray
    z: np.ndarray
    chi_red: float
    rho: float

    def findings(self, rms: float, sigma: float) -> list[Finding]:
        """``unexplained`` findings: correlated readings within the holds; hold means above the noise."""
        out = []
        if self.rho > 0.3:
            out.append(Finding("unexplained", "within_hold", "the readings within the holds are correlated in time "
                               f"(lag-1 autocorrelation {self.rho:.2f}; white gauge noise gives ~0): a disturbance "
                               "such as vibration, hum or a sliding contact that no modelled effect explains",
                               {"lag1_autocorrelation": self.rho}, {}, rms, rms, {}))
        if self.chi_red > 4.0 or rms > 1.5 * sigma:
            worst = self.keys[np.argmax(np.abs(self.z))]
            step_w, comp_w = worst // 4, worst % 4
            loc = f"axis:{'xyz'[comp_w]}"
            bad_steps = np.unique(self.keys[np.abs(self.z) > 4] // 4)
            if bad_steps.size:
                loc += f", step:{bad_steps.min()}-{bad_steps.max()}"
            out.append(Finding("unexplained", loc, "structure above the noise that no modelled effect explains "
                                                   f"(reduced chi-square of hold means {self.chi_red:.1f})",
                               {"reduced_chi2": self.chi_red}, {}, rms, rms, {"worst_hold": int(step_w)}))
        return out

    def hold_z2(self) -> dict:
        """{step: sum of squared z-scores of its hold means}"""
        steps = self.keys // 4
        return {int(k): float((self.z[steps == k] ** 2).sum()) for k in np.unique(steps)}

    def hold_offset_mm(self) -> dict:
        """{step: its largest hold-mean residual [mm]}"""
        steps = self.keys // 4
        return {int(k): float(self.mean_r[steps == k][np.argmax(np.abs(self.mean_r[steps == k]))])
                for k in np.unique(steps)}


def _lack_of_fit(data: RigSamples, resid: np.ndarray, sigma: float) -> _LackOfFit:
    keys = data.step * 4 + data.comp
    uk, inv = np.unique(keys, return_inverse=True)
    cnt = np.bincount(inv)
    mean_r = np.bincount(inv, weights=resid) / cnt
    z = mean_r * np.sqrt(cnt) / sigma
    return _LackOfFit(uk, mean_r, z, float(np.mean(z ** 2)), _within_hold_autocorrelation(data, resid))


def _within_hold_autocorrelation(data: RigSamples, resid: np.ndarray) -> float:
    """Pooled lag-1 autocorrelation of the residuals within each (hold, component), linear trend removed."""
    num = den = 0.0
    keys = data.step * 4 + data.comp
    for k in np.unique(keys):
        idx = np.nonzero(keys == k)[0]
        if idx.size < 6:
            continue
        idx = idx[np.argsort(data.t_abs[idx], kind="stable")]
        t, e = data.t_abs[idx], resid[idx]
        A = np.column_stack([np.ones_like(t), t - t.mean()])
        e = e - A @ np.linalg.lstsq(A, e, rcond=None)[0]
        num += float(e[1:] @ e[:-1])
        den += float(e @ e)
    return num / den if den > 0 else 0.0


def _explaining_order(ls, S: tuple) -> list:
    """The selected terms in the order they explain the residual: each next term is the one that, added to
    those before it, lowers the residual most (a term that only helps others never leads)."""
    order, rest = [], list(S)
    while rest:
        j = min(rest, key=lambda i: ls.fit(tuple(sorted(order + [i])))[1])
        order.append(j)
        rest.remove(j)
    return order
