"""Creep of two terms in a rig diagnosis: a laminate's fast creep and a bond's slow one.

The selection (:mod:`.rig_select`) keeps at most one creep term of one time constant. Where the creep has two,
the one term settles between them and what is left goes to a look-alike: a fast term (seconds) reaches its
share within each hold as a softer rod's deflection would, so it reads as a uniform scale beside a slow creep (the
independent rig simulator's two-term case was creep plus ``compliance_scale`` 1.013). After the selection,
:func:`two_term_step` tries one creep of two terms in place of the creep and such a look-alike (kept at a delta
BIC <= 0: one effect instead of two, at one more hidden parameter's cost), or in place of the creep alone
(kept only if it passes the test a new term passes: delta BIC <= -10, likelihood-ratio p <= 1e-3).

A creep of one term reports its amplitude's interval over the time constant's profile likelihood
(:func:`with_creep_profile`): with the time constant taken as known, an independent simulator's phi missed its
95 % interval by ~16 % in two cases of three.
"""
from __future__ import annotations

import dataclasses
import logging

import numpy as np
from scipy.optimize import minimize

from rodlab.stiffness_rig.effects import CREEP_TAU_GRID_S, two_term_creep_hypothesis
from rodlab.stiffness_rig.effects.creep import kelvin_voigt

from .criteria import bic_penalty, cv_improves, evidence
from .rig_select import admissible, subset_ls

__all__ = ["two_term_step", "with_creep_profile", "FAST_CREEP_LOOKALIKES"]

log = logging.getLogger(__name__)

#: effects a fast creep term can stand in for: its deflection is phi C F within seconds of each change of load
FAST_CREEP_LOOKALIKES = ("compliance_scale",)
#: the second time constant is at least this factor from the first (closer ones are one term)
TAU_RATIO_MIN = 3.0


def two_term_step(library, ls, S: tuple, data, base, r0, prep, sigma: float, folds):
    """(library, its SubsetLS, the chosen term indices), with one creep of two terms in place of the chosen
    creep (and a look-alike of its fast term) where the data say so; unchanged otherwise."""
    creep = [j for j in S if library[j].effect == "creep" and library[j].X.shape[1] == 1]
    if not creep:
        return library, ls, S
    j = creep[0]
    tau = float(library[j].settings["tau_s"])
    step_at = float(library[j].settings.get("load_step_at", 0.0))
    n = r0.size
    _, cur_rss = ls.fit(S)
    k_cur = sum(library[i].n_params for i in S)
    for drop, lenient in _replacements(library, S, j):
        rest = tuple(i for i in S if i not in drop)
        term = _best_second_term(library, rest, data, base, r0, prep, tau, step_at)
        if term is None:
            continue
        lib = library + [term]
        key = tuple(sorted(rest + (len(library),)))
        new_ls = subset_ls(lib, r0, folds)
        c, rss = new_ls.fit(key)
        dk = sum(lib[i].n_params for i in key) - k_cur
        dbic = (rss - cur_rss) / sigma ** 2 + dk * np.log(n)
        log.debug("two-term creep (%s) for %s: delta BIC %.1f", term.settings, [library[i].effect for i in drop], dbic)
        better = dbic <= 0 if lenient else evidence((cur_rss - rss) / sigma ** 2, dk, bic_penalty(dk, n)).significant
        if better and admissible(lib, new_ls, key, c, prep.detection) and cv_improves(ls.cv_error(S),
                                                                                          new_ls.cv_error(key)):
            log.info("creep of two terms (%s) in place of %s: delta BIC %.1f", term.settings,
                     [library[i].effect for i in drop], dbic)
            return lib, new_ls, key
    return library, ls, S


def _replacements(library, S: tuple, j: int):
    """(the chosen terms a two-term creep would replace, whether a delta BIC <= 0 keeps it): the creep and each
    look-alike of its fast term beside it, then the creep alone."""
    for k in S:
        if library[k].effect in FAST_CREEP_LOOKALIKES:
            yield (j, k), True
    yield (j,), False


def _best_second_term(library, rest: tuple, data, base, r0, prep, tau: float, step_at: float = 0.0):
    """The two-term creep that fits best beside the terms ``rest``: its time constants from the grid and the
    chosen one, at least :data:`TAU_RATIO_MIN` apart (the columns made once), then both refined continuously
    within half a grid step; None when there is no such pair."""
    taus = np.unique(np.append(CREEP_TAU_GRID_S, tau))
    K = prep.project_columns(kelvin_voigt(data, base, taus, step_at))
    others = np.column_stack([library[i].X for i in rest]) if rest else np.zeros((r0.size, 0))
    best = None
    for a in range(taus.size):
        for b in range(a + 1, taus.size):
            rss = _rss(others, K[:, [a, b]], r0) if taus[b] / taus[a] >= TAU_RATIO_MIN else np.inf
            if best is None or rss < best[0]:
                best = (rss, np.log([taus[b], taus[a]]))
    if not np.isfinite(best[0]):
        return None

    def rss(log_taus):
        return _rss(others, prep.project_columns(kelvin_voigt(data, base, np.exp(log_taus), step_at)), r0)

    step = 0.25 * np.log(2.0)                           # half the grid's step (a factor sqrt 2)
    res = minimize(rss, best[1], method="Nelder-Mead", bounds=[(v - step, v + step) for v in best[1]],
                   options={"xatol": 0.01, "fatol": 1e-12 * best[0], "maxfev": 60})
    slow, fast = np.exp(res.x if res.fun < best[0] else best[1])
    return prep(two_term_creep_hypothesis(data, base, float(slow), float(fast), step_at))


def _rss(others: np.ndarray, creep: np.ndarray, r0: np.ndarray) -> float:
    """Residual sum of squares of ``r0`` on the columns ``others`` and the two creep columns, inf where a creep
    amplitude comes out negative (a recovery, not creep)."""
    X = np.column_stack([others, creep])
    coef = np.linalg.lstsq(X, r0, rcond=None)[0]
    return float(np.sum((r0 - X @ coef) ** 2)) if np.all(coef[-2:] >= 0) else np.inf


#: the time constants of the profile: the chosen one times 2 ** (k / 16), k = -PROFILE_STEPS ... PROFILE_STEPS
#: (a factor 4 either way in steps of 4.4 %)
PROFILE_STEPS = 32
#: the profile keeps the time constants whose fit is within this chi-square of the chosen one's: 95 % for one
#: parameter, scipy.stats.chi2.ppf(0.95, 1) (written out: scipy.stats costs ~0.4 s of the command's start)
PROFILE_CHI2 = 3.841458820694124


def with_creep_profile(library, S: tuple, data, base, r0, prep, sigma: float) -> list:
    """``library`` with the chosen one-term creep's hypothesis carrying its profile (``Hypothesis.profile``): the
    time constants whose best fit beside the other chosen terms is within :data:`PROFILE_CHI2` of the chosen one's,
    their range as ``tau_s``'s interval and the union of phi's intervals over them as phi's (same columns: the
    selection's fits stand). The time constants are stepped outward from the chosen one until the fit leaves that
    range."""
    creep = [j for j in S if library[j].effect == "creep" and library[j].X.shape[1] == 1]
    if not creep:
        return library
    j = creep[0]
    others = [library[i].X for i in S if i != j]
    tau0 = float(library[j].settings["tau_s"])
    step_at = float(library[j].settings.get("load_step_at", 0.0))
    chosen = _phi_fit(others, library[j].X, r0, sigma)
    kept = [(tau0, chosen)]
    for direction in (-1.0, 1.0):
        for k in range(1, PROFILE_STEPS + 1):
            tau = tau0 * 2.0 ** (direction * k / 16.0)
            fit = _phi_fit(others, prep.project_columns(kelvin_voigt(data, base, np.array([tau]), step_at)), r0,
                           sigma)
            if (fit[0] - chosen[0]) / sigma ** 2 > PROFILE_CHI2 or fit[1] <= 0:
                break
            kept.append((tau, fit))
    phis = np.array([[f[1] - 1.96 * f[2], f[1] + 1.96 * f[2]] for _, f in kept])
    taus = [t for t, _ in kept]
    profile = {library[j].names[0]: (float(phis[:, 0].min()), float(phis[:, 1].max())),
               "tau_s": (float(min(taus)), float(max(taus)))}
    log.debug("creep profile over tau %s: %s", np.round(sorted(taus), 3), profile)
    out = list(library)
    out[j] = dataclasses.replace(library[j], profile=profile)
    prep.carry(library[j], out[j])
    return out


def _phi_fit(others: list, creep: np.ndarray, r0: np.ndarray, sigma: float) -> tuple[float, float, float]:
    """(residual sum of squares, phi, its standard error) of ``r0`` on the columns ``others`` and one creep
    column (the last)."""
    X = np.column_stack(others + [creep]) if others else creep
    coef, *_ = np.linalg.lstsq(X, r0, rcond=None)
    rss = float(np.sum((r0 - X @ coef) ** 2))
    cov = sigma ** 2 * np.linalg.pinv(X.T @ X)
    return rss, float(coef[-1]), float(np.sqrt(max(cov[-1, -1], 0.0)))
