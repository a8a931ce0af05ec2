"""Model selection of the rig diagnosis: which subset of the hypothesis library (:mod:`rodlab.stiffness_rig.effects`) the
recording supports.

Beam search over term subsets with bounded least squares from the Gram matrix (:mod:`.subset`), run by the
diagnosers' one selection routine (:mod:`.search`); a larger model replaces the current one only under the
acceptance rule shared with the campaign diagnosis (:mod:`.criteria`: delta BIC <= -10 with the known noise,
the likelihood-ratio p <= 1e-3, the leave-one-repeat-out prediction error drops); every term must change the
readings of a series by at least ``PTP_MIN`` noise SDs and stay off its physical bounds; a final drop-one test,
swaps, and a term that contains a simpler one of another effect is reduced to it unless its extra parameters pass
the acceptance rule.
Creep's time constant is refined continuously (:func:`refine_tau`). The gauge zero of each series is projected
out (:func:`demean`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from rodlab.core.enums import Trial
from rodlab.core.hypothesis import Hypothesis
from rodlab.stiffness_rig.effects import creep_hypothesis
from rodlab.stiffness_rig.samples import RigSamples
from .criteria import DBIC_MIN, bic_penalty, cv_improves, evidence, weakest_term
from .search import search
from .subset import SubsetLS

__all__ = ["select", "subset_ls", "refine_tau", "alternatives", "demean", "compatible", "admissible", "Detection",
           "PTP_MIN", "BEAM"]

log = logging.getLogger(__name__)

PTP_MIN = 1.0        # detection limit: peak-to-peak change of the readings of a series [noise SDs]


BEAM = 8


def compatible(library: list[Hypothesis], S: tuple, j: int) -> bool:
    """At most one term per (effect, location), one creep, one drift and one nonlinearity term (its forms are
    alternatives, not parts: two one-axis forms plus crosstalk once composed a gauge's own non-linearity)."""
    t = library[j]
    for i in S:
        u = library[i]
        if u.effect == t.effect and (u.location == t.location or t.effect in ("creep", "drift", "nonlinearity")):
            return False
    return True


@dataclass(frozen=True)
class Detection:
    """What a term must change to be seen: ``groups`` (n,) the series of each reading (gauge zeros), ``floor_mm``
    the noise of what a term changes [mm]: one reading's, or a hold mean's scatter where that is larger (the
    hold-to-hold repeatability); never the selection's inflated per-reading sigma (a blind trial: 0.3 um of
    repeatability had raised the floor to 2.8 um and hidden a load non-linearity, a tilted gauge and a small
    friction)."""

    groups: np.ndarray
    floor_mm: float


def admissible(library, ls: SubsetLS, S: tuple, coef, detect: Detection) -> bool:
    """Every term changes the readings of some series by >= PTP_MIN noise SDs peak to peak (detection limit,
    ``detect``) and none sits on a physical bound (then it is not this physics)."""
    groups = detect.groups
    k = 0
    for j, contrib in zip(S, ls.contribution(S, coef)):
        t = library[j]
        val = coef[k:k + t.X.shape[1]]
        k += t.X.shape[1]
        if max(np.ptp(contrib[groups == g]) for g in np.unique(groups)) < PTP_MIN * detect.floor_mm:
            return False
        if np.any((np.abs(val - t.upper) < 1e-9 * np.maximum(1, np.abs(t.upper))) & (t.upper != 0)):
            return False
    return True


def select(library: list[Hypothesis], ls: SubsetLS, sigma: float, n: int, max_terms: int, detect: Detection) -> tuple:
    """Beam search over term subsets (width ``BEAM``) by the diagnosers' selection routine (:func:`.search.search`).
    The best admissible subset of each size replaces the current model only if delta BIC <= -10, the
    likelihood-ratio p < 1e-3 and the cross-validated error drops; subsets need not nest, so a strong but wrong
    first term does not lock in the path. Then terms that are no longer needed in the final model (drop-one
    test) are removed, and terms swapped while that lowers the BIC."""
    space = _RigSpace(library, ls, sigma, n, detect)
    search(space, max_terms)
    return space.cur


class _RigSpace:
    """The rig's :class:`~.search.SearchSpace`: a beam of the best subsets of each size; candidates are
    ``(subset, coefficients, rss)``."""

    tries = 4 * BEAM
    keep_growing = True

    def __init__(self, library: list[Hypothesis], ls: SubsetLS, sigma: float, n: int, detect: Detection) -> None:
        self.library, self.ls, self.sigma, self.n, self.detect = library, ls, sigma, n, detect
        self.npar = [t.n_params for t in library]
        self.cur: tuple = ()
        self.cur_rss = ls.fit(self.cur)[1]
        self.cur_cv = ls.cv_error(self.cur)
        self.beam: list[tuple] = [()]

    def k_of(self, S: tuple) -> int:
        return sum(self.npar[j] for j in S)

    def exhausted(self) -> bool:
        return False

    def grow(self) -> list:
        """Every compatible one-term extension of the beam, fitted and ranked by BIC; the beam moves to the best
        ``BEAM`` of them."""
        cands = {}
        for S in self.beam:
            for j in range(len(self.library)):
                if j in S or not compatible(self.library, S, j):
                    continue
                key = tuple(sorted(S + (j,)))
                if key not in cands:
                    c, rss = self.ls.fit(key)
                    cands[key] = (rss / self.sigma ** 2 + self.k_of(key) * np.log(self.n), c, rss)
        ranked = sorted(cands.items(), key=lambda kv: kv[1][0])
        self.beam = [key for key, _ in ranked[:BEAM]]
        return [(key, c, rss) for key, (_, c, rss) in ranked]

    def trial(self, candidate) -> Trial:
        """An inadmissible subset lets the next try; the best admissible one is the step's only chance."""
        key, c, rss = candidate
        if not admissible(self.library, self.ls, key, c, self.detect):
            return Trial.NEXT
        dk = self.k_of(key) - self.k_of(self.cur)
        if not evidence((self.cur_rss - rss) / self.sigma ** 2, dk, bic_penalty(dk, self.n)).significant:
            return Trial.END_STEP
        cv = self.ls.cv_error(key)
        if not cv_improves(self.cur_cv, cv):
            log.info("%s rejected: cross-validated error does not drop", [self.library[j].effect for j in key])
            return Trial.END_STEP
        self.cur, self.cur_rss, self.cur_cv = key, rss, cv
        return Trial.ACCEPT

    def finish(self) -> None:
        """Drop-one test (remove the weakest term while it fails), then swaps (:func:`_swap`)."""
        def without(j):
            return tuple(i for i in self.cur if i != j)

        while self.cur:
            j = weakest_term(self.cur, lambda j: (self.ls.fit(without(j))[1] - self.cur_rss) / self.sigma ** 2,
                             lambda j: self.npar[j], self.n)
            if j is None:
                break
            self.cur = without(j)
            self.cur_rss = self.ls.fit(self.cur)[1]
        self.cur = _swap(self.library, self.ls, self.cur, self.sigma, self.n, self.detect, self.k_of)
        self.cur = _nested_simpler(self.library, self.ls, self.cur, self.sigma, self.n, self.detect)


def _spans(X: np.ndarray, Y: np.ndarray) -> bool:
    """Whether the columns of ``Y`` lie in the span of those of ``X`` (to round-off)."""
    coef = np.linalg.lstsq(X, Y, rcond=None)[0]
    return bool(np.linalg.norm(Y - X @ coef) <= 1e-8 * max(np.linalg.norm(Y), 1e-300))


def _nested_simpler(library, ls: SubsetLS, cur: tuple, sigma: float, n: int, detect: Detection) -> tuple:
    """Replace a term that contains a simpler term of another effect (its columns span the other's: a joint
    spring on pipe I has pipe I's torsion as its torsion part) by that simpler term, unless its extra parameters
    pass the test a new term must pass (delta BIC <= -10, likelihood-ratio p <= 1e-3): the data then say no more
    than the simpler physics. (The plain-BIC swaps keep an extra parameter that gains ~ln n in chi-square.) Each
    step lowers the parameter count, so this ends."""
    _, cur_rss = ls.fit(cur)
    while (step := _simpler_term(library, ls, cur, cur_rss, sigma, n, detect)) is not None:
        cur, cur_rss = step
    return cur


def _simpler_term(library, ls: SubsetLS, cur: tuple, cur_rss: float, sigma: float, n: int, detect: Detection):
    """The first reduction of :func:`_nested_simpler` of the model ``cur``: (the new model, its residual sum of
    squares), or None."""
    for j in cur:
        t, rest = library[j], tuple(i for i in cur if i != j)
        for i, u in enumerate(library):
            if (u.effect == t.effect or i in cur or u.n_params >= t.n_params or not compatible(library, rest, i)
                    or not _spans(t.X, u.X)):
                continue
            key = tuple(sorted(rest + (i,)))
            c, rss = ls.fit(key)
            dk = t.n_params - u.n_params
            if (not evidence((rss - cur_rss) / sigma ** 2, dk, bic_penalty(dk, n)).significant
                    and admissible(library, ls, key, c, detect)):
                log.info("nested: %s -> %s", t.label, u.label)
                return key, rss
    return None


def _swap(library, ls: SubsetLS, cur: tuple, sigma: float, n: int, detect: Detection, k_of) -> tuple:
    """Replace one term of the final model by another while that lowers the BIC and keeps the model
    admissible with a cross-validated error no worse: a beam whose early slots went to a look-alike (a new
    hypothesis that resembles two others) can end on a neighbour of the best model of its size."""
    def bic(S, rss):
        return rss / sigma ** 2 + k_of(S) * np.log(n)

    _, cur_rss = ls.fit(cur)
    for _ in range(len(cur) + 1):
        best = None
        for j in cur:
            rest = tuple(i for i in cur if i != j)
            for i in range(len(library)):
                if i in cur or not compatible(library, rest, i):
                    continue
                key = tuple(sorted(rest + (i,)))
                c, rss = ls.fit(key)
                if bic(key, rss) < bic(cur, cur_rss) - 1e-9 and (best is None or bic(key, rss) < bic(*best[:2])):
                    if admissible(library, ls, key, c, detect):
                        best = (key, rss)
        if best is None:
            break
        cv_new, cv_cur = ls.cv_error(best[0]), ls.cv_error(cur)
        if np.isfinite(cv_cur) and not cv_new <= cv_cur * (1 + 1e-12):
            break
        log.info("swap: %s -> %s", [library[j].effect for j in cur], [library[j].effect for j in best[0]])
        cur, cur_rss = best
    return cur


def subset_ls(library: list[Hypothesis], r0: np.ndarray, folds) -> SubsetLS:
    blocks, p0 = [], 0
    for t in library:
        blocks.append(np.arange(p0, p0 + t.X.shape[1]))
        p0 += t.X.shape[1]
    return SubsetLS(np.column_stack([t.X for t in library]), r0, blocks,
                    np.concatenate([t.lower for t in library]), np.concatenate([t.upper for t in library]), folds)


def refine_tau(library, S: tuple, j: int, data: RigSamples, base, r0, prep) -> float:
    """Creep time constant [s] minimising the residual of the model ``S`` (bounded, in log tau); ``prep`` projects a
    new term's columns as the library's were (gauge zeros, and the free linear part where it is fitted)."""
    others = [library[i] for i in S if i != j]
    step_at = float(library[j].settings.get("load_step_at", 0.0))

    def rss(log_tau):
        term = prep(creep_hypothesis(data, base, float(np.exp(log_tau)), step_at=step_at))
        return subset_ls(others + [term], r0, None).fit(tuple(range(len(others) + 1)))[1]

    t0 = np.log(library[j].settings["tau_s"])
    res = minimize_scalar(rss, bounds=(t0 - 0.5 * np.log(2), t0 + 0.5 * np.log(2)), method="bounded",
                          options={"xatol": 0.01})
    return float(np.exp(res.x))


def alternatives(library, ls: SubsetLS, S: tuple, j: int, rss: float, sigma: float, n: int) -> list:
    """Terms of another effect that, put in place of term ``j``, fit within delta BIC 10: the data cannot
    tell them apart (e.g. creep with a time constant well below the hold time looks like a uniform scale)."""
    out = []
    rest = tuple(i for i in S if i != j)
    for i, u in enumerate(library):
        if u.effect == library[j].effect or i in S or not compatible(library, rest, i):
            continue
        _, rss_alt = ls.fit(tuple(sorted(rest + (i,))))
        dbic = (rss_alt - rss) / sigma ** 2 + (u.n_params - library[j].n_params) * np.log(n)
        if dbic < DBIC_MIN:
            out.append(u.label)
    return out


def demean(a: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """``a`` (n,) or (n, k) minus its mean within each group."""
    _, inv = np.unique(groups, return_inverse=True)
    cnt = np.bincount(inv).astype(float)
    a2 = a.reshape(a.shape[0], -1)
    means = np.stack([np.bincount(inv, weights=a2[:, j]) / cnt for j in range(a2.shape[1])], axis=1)
    return (a2 - means[inv]).reshape(a.shape)
