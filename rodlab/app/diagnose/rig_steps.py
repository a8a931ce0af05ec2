"""The steps a rig diagnosis shares whether or not the simulation is taken to be exact: the noise of a reading,
the selection with creep's time constant refined, the findings of the chosen terms, the lack of fit left."""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rodlab.core.enums import FindingKind
from rodlab.core.hypothesis import Hypothesis
from rodlab.stiffness_rig.effects import creep_hypothesis
from rodlab.stiffness_rig.samples import RigSamples

from .criteria import DBIC_MIN, bic_penalty, evidence
from .report import Finding
from .rig_creep import two_term_step, with_creep_profile
from .rig_outside import OUTSIDE
from .rig_select import Detection, alternatives, compatible, demean, refine_tau, select, subset_ls

__all__ = ["RigModelFit", "Prep", "select_refining_creep", "term_findings", "LackOfFit",
           "lack_of_fit", "LACK_CHI_RED"]

log = logging.getLogger(__name__)

#: reduced chi-square of the hold means above which structure is left that nothing modelled explains
LACK_CHI_RED = 4.0


class Prep:
    """Project a hypothesis' columns as the library's are: off each series' gauge zero and, where the linear part
    is fitted freely, off that too (``project``); the columns before projection (gauge zeros only) are kept by
    term, for the fitted change of the readings. ``detection``: the series and the noise floor [mm] a term must
    change the readings by to be seen (:class:`.rig_select.Detection`)."""

    def __init__(self, groups: np.ndarray, project=None, floor_mm: float = 0.0) -> None:
        self.groups, self.project, self.raw = groups, project, {}
        self.detection = Detection(groups, floor_mm)

    def __call__(self, term: Hypothesis) -> Hypothesis:
        self.raw[id(term)] = demean(term.X, self.groups)
        term.X = self.project(term.X) if self.project is not None else self.raw[id(term)]
        return term

    def carry(self, old: Hypothesis, new: Hypothesis) -> None:
        """``new`` (a copy of ``old`` with the same columns) keeps ``old``'s columns before projection."""
        if id(old) in self.raw:
            self.raw[id(new)] = self.raw[id(old)]

    def project_columns(self, X: np.ndarray) -> np.ndarray:
        """Columns ``X`` (n, k) projected as a hypothesis' are (gauge zeros, the free linear part)."""
        X = demean(X, self.groups)
        return self.project(X) if self.project is not None else X

    def raw_columns(self, terms) -> np.ndarray:
        """The terms' columns before projection (gauge zeros removed), shape=(n, p)."""
        return np.column_stack([self.raw[id(t)] for t in terms]) if terms else np.zeros((0, 0))

    def fitted_change(self, terms, coef: np.ndarray) -> np.ndarray:
        """The change of every reading the fitted terms make (gauge zeros removed) [mm]."""
        if not terms:
            return 0.0
        return np.column_stack([self.raw[id(t)] for t in terms]) @ coef


@dataclass
class RigModelFit:
    """The model a rig diagnosis chose, for export and figures.

    terms : the chosen hypotheses (:class:`~rodlab.core.hypothesis.Hypothesis`); coef : their fitted internal
    parameters, concatenated in ``terms`` order; resid : residual of every sample after the fit [mm];
    base_resid : residual against the simulated compliance alone (gauge zeros removed) [mm]; data : the samples
    (:class:`~rodlab.stiffness_rig.samples.RigSamples`); sigma : noise of one reading [mm]; hold_z2 : {step: sum of
    squared z-scores of its hold means}; hold_offset_mm : {step: largest hold-mean residual [mm]};
    linear : the freely fitted linear compliance
    (:class:`~.rig_linear.LinearPart`) where the simulation was not taken to be exact, else None
    """

    terms: list
    coef: np.ndarray
    resid: np.ndarray
    base_resid: np.ndarray
    data: RigSamples
    sigma: float
    hold_z2: dict
    hold_offset_mm: dict
    linear: object = None

    def term_values(self):
        """(hypothesis, its fitted internal parameters) of every chosen term."""
        k = 0
        for term in self.terms:
            yield term, self.coef[k:k + term.X.shape[1]]
            k += term.X.shape[1]


def select_refining_creep(library, ls, data: RigSamples, base, r0, prep: Prep, sigma: float, max_terms: int,
                          folds):
    """Select a model; creep's time constant was picked from a grid: refine it continuously in the chosen model
    and in each of its sub-models that keep creep, then select again among the refined ones (a grid mismatch
    at high SNR must not be patched with extra terms such as a compliance scale); then a creep of two terms is
    tried in its place (:func:`.rig_creep.two_term_step`). Returns (library, its :class:`SubsetLS`, the chosen term
    indices)."""
    S = select(library, ls, sigma, r0.size, max_terms, prep.detection)
    for _ in range(2):
        creep = [j for j in S if library[j].effect == "creep"]
        if not creep:
            break
        j = creep[0]
        taus = []
        for sub in [S] + [tuple(i for i in S if i != k) for k in S if k != j]:
            tau = refine_tau(library, sub, j, data, base, r0, prep)
            if all(abs(np.log(tau / t)) > 0.01 for t in taus):
                taus.append(tau)
        if all(abs(np.log(t / library[j].settings["tau_s"])) < 0.01 for t in taus):
            break
        step_at = float(library[j].settings.get("load_step_at", 0.0))
        refined = []
        for tau in taus:
            refined.append(prep(creep_hypothesis(data, base, tau, step_at=step_at)))
        library = [t for t in library if t.effect != "creep"] + refined
        ls = subset_ls(library, r0, folds)
        S = select(library, ls, sigma, r0.size, max_terms, prep.detection)
    library, ls, S = two_term_step(library, ls, S, data, base, r0, prep, sigma, folds)
    return with_creep_profile(library, S, data, base, r0, prep, sigma), ls, S


def term_findings(library, ls, S: tuple, coef, rss: float, sigma: float, rss0: float) -> list[Finding]:
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
        places = _other_places(library, ls, S, j, rss, sigma) if term.effect in _SEPARATE_BY else []
        if places:
            location = "|".join([term.location] + places)
            kinds = {p.split(":")[0] for p in [term.location] + places}
            if term.effect != "crosstalk" or kinds == {"sensor", "load"}:
                ev["separate_by"] = _SEPARATE_BY[term.effect]
        alts_j = alternatives(library, ls, S, j, rss, sigma, n)
        if alts_j:
            ev["alternatives"] = alts_j
        if term.effect == OUTSIDE:
            ev["outside_vocabulary"] = True
        params, intervals = term.reported(val, se)
        at_bound = [name for name, v, lo, hi in zip(term.names, val, term.lower, term.upper)
                    if any(np.isfinite(b) and abs(v - b) <= 1e-9 * max(1.0, abs(b)) for b in (lo, hi))]
        if at_bound:                      # a bound holds it: the interval of the fit says nothing
            ev["at_bound"] = at_bound
        findings.append(Finding(term.effect, location, term.explanation, params, intervals,
                                float(np.sqrt(rss_prev / n)), float(np.sqrt(rss_m / n)), ev))
        rss_prev = rss_m
    return findings


#: effects whose places compete (the others of a place fitting within delta BIC 10 are named with it) and the
#: measurement that tells the places apart
_SEPARATE_BY = {
    "joint_compliance": ("load along x_T with the x gauge (pipe I bending) and along y_T (torsion): the lever from "
                         "each place to the ball differs in each"),
    "crosstalk": ("read the gauge under a second load axis: a tilted gauge errs in every series it reads, a tilted "
                  "load line only in its own"),
}


def _other_places(library, ls, S: tuple, j: int, rss: float, sigma: float) -> list[str]:
    """Ambiguity among places: the other places of term ``j``'s effect (joint springs, tilted gauges and load
    lines) that, put in place of term ``j``, fit within delta BIC 10."""
    alts = []
    for i, u in enumerate(library):
        if u.effect == library[j].effect and i != j and u.location != library[j].location:
            alt = tuple(sorted([x for x in S if x != j] + [i]))
            if len(set(alt)) == len(alt) and all(compatible(library, tuple(x for x in alt if x != y), y)
                                                 for y in alt):
                if u.location not in alts and (ls.fit(alt)[1] - rss) / sigma ** 2 < DBIC_MIN:
                    alts.append(u.location)
    return alts


@dataclass
class LackOfFit:
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
            out.append(Finding(FindingKind.UNEXPLAINED, "within_hold", "the readings within the holds are correlated in time "
                               f"(lag-1 autocorrelation {self.rho:.2f}; white gauge noise gives ~0): a disturbance "
                               "such as vibration, hum or a sliding contact that no modelled effect explains",
                               {"lag1_autocorrelation": self.rho}, {}, rms, rms, {}))
        if self.chi_red > LACK_CHI_RED or rms > 1.5 * sigma:
            worst = self.keys[np.argmax(np.abs(self.z))]
            step_w, comp_w = worst // 4, worst % 4
            loc = f"axis:{'xyz'[comp_w]}"
            bad_steps = np.unique(self.keys[(np.abs(self.z) > 4) & (self.keys % 4 == comp_w)] // 4)   # that gauge's
            if bad_steps.size:
                loc += f", step:{bad_steps.min()}-{bad_steps.max()}"
            out.append(Finding(FindingKind.UNEXPLAINED, loc, "structure above the noise that no modelled effect explains "
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


def lack_of_fit(data: RigSamples, resid: np.ndarray, sigma: float, C: np.ndarray) -> LackOfFit:
    """The hold means' residuals against their own scatter: the gauges' noise and, where a load cell measured the
    load, the error of the hold's mean force through the compliance ``C`` [mm/N]."""
    keys = data.step * 4 + data.comp
    uk, inv = np.unique(keys, return_inverse=True)
    cnt = np.bincount(inv)
    mean_r = np.bincount(inv, weights=resid) / cnt
    load_sd = np.abs(np.asarray(C, float)[data.comp, data.axis]) * data.F_se
    load_var = np.bincount(inv, weights=load_sd ** 2) / cnt
    z = mean_r / np.sqrt(sigma ** 2 / cnt + load_var)
    return LackOfFit(uk, mean_r, z, float(np.mean(z ** 2)), _within_hold_autocorrelation(data, resid))


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
