"""Diagnosis of a stiffness-rig recording against the simulated compliance of its rod.

1. Screen: the noise of one reading from the within-hold scatter (detrended per hold; never from a model
   fit); the simulated model's residuals.
2. Attribute: a beam search over subsets of the hypothesis library (:mod:`.rig_terms`), each term fitted
   with physical bounds (bounded linear least squares, :mod:`.subset`). A larger model replaces the current
   one only if delta BIC <= -10 (known noise), the likelihood-ratio test gives p < 1e-3 and the
   leave-one-repeat-out prediction error drops; every term must change a reading by >= 2 noise SDs and stay
   off its physical bounds, and must pass a drop-one test in the final model; at most ``max_terms`` terms.
3. Locate: joint springs at the candidate places compete; when the runner-up fits within delta BIC 10 the
   finding names the group and the measurement that would separate them.
4. Explain: parameters with 95 % intervals, a sentence of physics; structure left above the noise (reduced
   chi-square of the hold means) makes the verdict ``unexplained`` with where it is.
"""
from __future__ import annotations

import logging

import numpy as np
from scipy.optimize import lsq_linear
from scipy.stats import chi2

from ..compliance import RodCompliance
from ..enums import Phase
from ..units import G0
from .report import Diagnosis, Finding
from .rig_terms import RigData, Term, creep_term, rig_terms
from .subset import SubsetLS

__all__ = ["rig_data", "diagnose_rig", "joint_places"]

log = logging.getLogger(__name__)

DBIC_MIN = 10.0
P_MAX = 1e-3
PTP_MIN = 1.0        # detection limit: peak-to-peak change of the readings of a series [noise SDs]


def rig_data(rec) -> RigData:
    """Flatten a recording into one row per measured reading."""
    rows = []
    series_start, series_temp, hold_start = {}, {}, {}
    first_step = {}
    for i in range(rec.n):
        ax = rec.load_axis[i]
        if ax not in series_start:
            series_start[ax] = rec.time_s[i]
            series_temp[ax] = rec.temp_C[i] if rec.temp_C is not None else np.nan
            first_step[ax] = rec.step[i]
        hold_start.setdefault(rec.step[i], rec.time_s[i])
    for c in range(3):
        m = np.isfinite(rec.disp_mm[:, c])
        idx = np.nonzero(m)[0]
        for i in idx:
            ax = rec.load_axis[i]
            rows.append((rec.disp_mm[i, c], c, ax.index, ax.sign, rec.mass_kg[i] * G0 * ax.sign, rec.mass_kg[i],
                         rec.phase[i] is Phase.UNLOAD, rec.step[i] == first_step[ax] and rec.mass_kg[i] == 0,
                         rec.time_s[i] - hold_start[rec.step[i]], rec.time_s[i] - series_start[ax],
                         (rec.temp_C[i] - series_temp[ax]) if rec.temp_C is not None else np.nan, rec.step[i],
                         rec.repeat[i], rec.time_s[i]))
    a = list(zip(*rows))
    d = RigData(np.array(a[0]), np.array(a[1], int), np.array(a[2], int), np.array(a[3], float), np.array(a[4]),
                np.array(a[5]), np.array(a[6], bool), np.array(a[7], bool), np.array(a[8]), np.array(a[9]),
                np.array(a[10], float), np.array(a[11], int), np.array(a[12], int), np.array(a[13]))
    d.temp_rel = d.temp
    return d


def within_hold_noise(data: RigData) -> float:
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


def joint_places(tool_mm, design=None) -> dict:
    """Candidate places of a compliant joint, in {T}: (point, member axis)."""
    tool = np.asarray(tool_mm, float)
    if design is not None:
        from ..layout import layout
        segs = layout(design)
        pts = {}
        ring1 = [s for s in segs if any(str(l.part) == "ring_1" for l in s.layers)]
        pts["flange_clamp"] = (segs[0].start_F - tool, segs[0].direction)
        if ring1:
            pts["ring_1"] = (ring1[0].point([ring1[0].length_mm / 2])[0] - tool, ring1[0].direction)
        p2 = [s for s in segs if any(str(l.part) == "pipe_II" for l in s.layers)]
        if p2:
            s = p2[len(p2) // 2]
            pts["pipe_II"] = (s.point([s.length_mm / 2])[0] - tool, s.direction)
        return pts
    # without a design: an L-rod with pipe I along z, pipe II towards the ball
    L1 = tool[2] if tool[0] > 0 else tool[2] / 2
    u2 = tool - np.array([0.0, 0.0, L1])
    u2 = u2 / max(np.linalg.norm(u2), 1e-9)
    return {"flange_clamp": (-tool, np.array([0.0, 0.0, 1.0])),
            "ring_1": (np.array([0.0, 0.0, 0.78 * L1]) - tool, np.array([0.0, 0.0, 1.0])),
            "pipe_II": (np.array([0.0, 0.0, L1]) + 0.5 * np.linalg.norm(tool - [0, 0, L1]) * u2 - tool, u2)}


BEAM = 8


def _compatible(library: list[Term], S: tuple, j: int) -> bool:
    """At most one term per (effect, location), one creep and one drift term."""
    t = library[j]
    for i in S:
        u = library[i]
        if u.effect == t.effect and (u.location == t.location or t.effect in ("creep", "drift")):
            return False
    return True


def _admissible(library, ls: SubsetLS, S: tuple, coef, sigma: float, groups: np.ndarray) -> bool:
    """Every term changes the readings of some series by >= PTP_MIN noise SDs peak to peak (detection limit) and
    none sits on a physical bound (then it is not this physics)."""
    k = 0
    for j, contrib in zip(S, ls.contribution(S, coef)):
        t = library[j]
        val = coef[k:k + t.X.shape[1]]
        k += t.X.shape[1]
        if max(np.ptp(contrib[groups == g]) for g in np.unique(groups)) < PTP_MIN * sigma:
            return False
        if np.any((np.abs(val - t.upper) < 1e-9 * np.maximum(1, np.abs(t.upper))) & (t.upper != 0)):
            return False
    return True


def _select(library: list[Term], ls: SubsetLS, sigma: float, n: int, max_terms: int, groups) -> tuple:
    """Beam search over term subsets (width ``BEAM``). The best admissible subset of each size replaces the
    current model only if delta BIC <= -10, the likelihood-ratio p < 1e-3 and the cross-validated error drops;
    subsets need not nest, so a strong but wrong first term does not lock in the path. Then terms that are no
    longer needed in the final model (drop-one test) are removed."""
    npar = [t.n_params for t in library]

    def k_of(S):
        return sum(npar[j] for j in S)

    cur = ()
    _, cur_rss = ls.fit(cur)
    cur_cv = ls.cv_error(cur)
    beam = [()]
    for _ in range(max_terms):
        cands = {}
        for S in beam:
            for j in range(len(library)):
                if j in S or not _compatible(library, S, j):
                    continue
                key = tuple(sorted(S + (j,)))
                if key not in cands:
                    c, rss = ls.fit(key)
                    cands[key] = (rss / sigma ** 2 + k_of(key) * np.log(n), c, rss)
        if not cands:
            break
        ranked = sorted(cands.items(), key=lambda kv: kv[1][0])
        beam = [key for key, _ in ranked[:BEAM]]
        best = next(((key, c, rss) for key, (_, c, rss) in ranked[:4 * BEAM]
                     if _admissible(library, ls, key, c, sigma, groups)), None)
        if best is None:
            continue
        key, c, rss = best
        dk = k_of(key) - k_of(cur)
        lr = (cur_rss - rss) / sigma ** 2
        if -lr + dk * np.log(n) > -DBIC_MIN or chi2.sf(max(lr, 0.0), max(dk, 1)) > P_MAX:
            continue
        cv = ls.cv_error(key)
        if np.isfinite(cur_cv) and not cv < cur_cv:
            log.info("%s rejected: cross-validated error does not drop", [library[j].effect for j in key])
            continue
        cur, cur_rss, cur_cv = key, rss, cv
    # backward: remove the weakest term while its drop-one test fails
    while cur:
        weakest = None
        for j in cur:
            rest = tuple(i for i in cur if i != j)
            _, rss_r = ls.fit(rest)
            lr = (rss_r - cur_rss) / sigma ** 2
            ok = -lr + npar[j] * np.log(n) <= -DBIC_MIN and chi2.sf(max(lr, 0.0), npar[j]) <= P_MAX
            if not ok and (weakest is None or lr < weakest[1]):
                weakest = (rest, lr, rss_r)
        if weakest is None:
            break
        cur, cur_rss = weakest[0], weakest[2]
    return cur


def diagnose_rig(rec, sim: RodCompliance, design=None, max_terms: int = 3) -> tuple[Diagnosis, dict]:
    """Diagnose ``rec`` against ``sim``; returns the report and the fitted model (for export and figures)."""
    data = rig_data(rec)
    sigma = within_hold_noise(data)
    n = data.y.size
    base = sim.C_F[data.comp, data.axis] * data.F
    library = rig_terms(data, sim.C_F, joint_places(sim.tool_mm, design), sim.tool_mm)
    # the zero of each gauge in each series is a nuisance parameter (it was set on one noisy, quantised
    # reading): project it out of the residual and of every term's columns (Frisch-Waugh)
    groups = data.axis * 4 + data.comp
    r0 = _demean(data.y - base, groups)
    for t in library:
        t.X = _demean(t.X, groups)
    folds = data.repeat if np.unique(data.repeat).size >= 2 else None
    ls = _subset_ls(library, r0, folds)
    rms0 = float(np.sqrt(r0 @ r0 / n))
    S = _select(library, ls, sigma, n, max_terms, groups)
    for _ in range(2):
        # creep's time constant was picked from a grid: refine it continuously in the chosen model and in
        # each of its sub-models that keep creep, then select again among the refined ones (a grid mismatch
        # at high SNR must not be patched with extra terms such as a compliance scale)
        creep = [j for j in S if library[j].effect == "creep"]
        if not creep:
            break
        j = creep[0]
        taus = []
        for sub in [S] + [tuple(i for i in S if i != k) for k in S if k != j]:
            tau = _refine_tau(library, sub, j, data, base, r0, groups)
            if all(abs(np.log(tau / t)) > 0.01 for t in taus):
                taus.append(tau)
        if all(abs(np.log(t / library[j].extra_tau)) < 0.01 for t in taus):
            break
        refined = []
        for tau in taus:
            refined.append(creep_term(data, base, tau))
            refined[-1].X = _demean(refined[-1].X, groups)
        library = [t for t in library if t.effect != "creep"] + refined
        ls = _subset_ls(library, r0, folds)
        S = _select(library, ls, sigma, n, max_terms, groups)
    coef, rss = ls.fit(S)
    cv_full = ls.cv_error(S)
    # strength of each term: the likelihood ratio of dropping it from the final model
    drop = {}
    for j in S:
        rest = tuple(i for i in S if i != j)
        _, rss_r = ls.fit(rest)
        drop[j] = ((rss_r - rss) / sigma ** 2, ls.cv_error(rest))
    order = sorted(S, key=lambda j: -drop[j][0])
    cols = ls.columns(S)
    Gn = ls.G[np.ix_(cols, cols)] * np.outer(ls.norms[cols], ls.norms[cols])
    se_all = np.sqrt(np.clip(np.diag(sigma ** 2 * np.linalg.pinv(Gn)), 0, None))
    offsets = dict(zip(S, np.cumsum([0] + [library[j].X.shape[1] for j in S])[:-1]))
    findings = []
    rss_prev = float(r0 @ r0)
    for m, j in enumerate(order):
        term = library[j]
        kj = term.X.shape[1]
        val, se = coef[offsets[j]:offsets[j] + kj], se_all[offsets[j]:offsets[j] + kj]
        _, rss_m = ls.fit(tuple(sorted(order[:m + 1])))
        lr = drop[j][0]
        evidence = {"delta_bic": float(-lr + term.n_params * np.log(n)), "lr_chi2": float(lr),
                    "lr_p": float(chi2.sf(max(lr, 0.0), term.n_params)), "cv_sse_before": float(drop[j][1]),
                    "cv_sse_after": float(cv_full)}
        location = term.location
        if term.effect == "joint_compliance":
            # ambiguity among places: another place fits within delta BIC 10
            alts = []
            for i, u in enumerate(library):
                if u.effect == "joint_compliance" and i != j:
                    alt = tuple(sorted([x for x in S if x != j] + [i]))
                    if len(set(alt)) == len(alt) and all(_compatible(library, tuple(x for x in alt if x != y), y)
                                                         for y in alt):
                        if (ls.fit(alt)[1] - rss) / sigma ** 2 < DBIC_MIN:
                            alts.append(u.location)
            if alts:
                location = "|".join([term.location] + alts)
                evidence["separate_by"] = ("load along x_T with the x gauge (pipe I bending) and along y_T (torsion): "
                                           "the lever from each place to the ball differs in each")
        alternatives = _alternatives(library, ls, S, j, rss, sigma, n)
        if alternatives:
            evidence["alternatives"] = alternatives
        params, intervals = _report_params(term, val, se)
        findings.append(Finding(term.effect, location, term.explanation, params, intervals,
                                float(np.sqrt(rss_prev / n)), float(np.sqrt(rss_m / n)), evidence))
        rss_prev = rss_m
    chosen = [library[j] for j in S]
    resid = ls.residual(S, coef)
    rms = float(np.sqrt(rss / n))
    # lack of fit of the hold means: structure the library does not explain
    keys = data.step * 4 + data.comp
    uk, inv = np.unique(keys, return_inverse=True)
    cnt = np.bincount(inv)
    mean_r = np.bincount(inv, weights=resid) / cnt
    z = mean_r * np.sqrt(cnt) / sigma
    chi_red = float(np.mean(z ** 2))
    rho = _within_hold_autocorrelation(data, resid)
    verdict = "consistent" if not findings else "explained"
    if rho > 0.3:
        findings.append(Finding("unexplained", "within_hold", "the readings within the holds are correlated in time "
                                f"(lag-1 autocorrelation {rho:.2f}; white gauge noise gives ~0): a disturbance such as "
                                "vibration, hum or a sliding contact that no modelled effect explains",
                                {"lag1_autocorrelation": rho}, {}, rms, rms, {}))
        verdict = "unexplained"
    if chi_red > 4.0 or rms > 1.5 * sigma:
        worst = uk[np.argmax(np.abs(z))]
        step_w, comp_w = worst // 4, worst % 4
        loc = f"axis:{'xyz'[comp_w]}"
        bad_steps = np.unique(uk[np.abs(z) > 4] // 4)
        if bad_steps.size:
            loc += f", step:{bad_steps.min()}-{bad_steps.max()}"
        findings.append(Finding("unexplained", loc, "structure above the noise that no modelled effect explains "
                                                    f"(reduced chi-square of hold means {chi_red:.1f})",
                                {"reduced_chi2": chi_red}, {}, rms, rms, {"worst_hold": int(step_w)}))
        verdict = "unexplained"
    model = {"terms": chosen, "coef": coef, "resid": resid, "base_resid": r0, "data": data, "sigma": sigma}
    return Diagnosis("rig", verdict, sigma, rms0, rms, findings, {"reduced_chi2_hold_means": chi_red}), model


def _subset_ls(library: list[Term], r0: np.ndarray, folds) -> SubsetLS:
    blocks, p0 = [], 0
    for t in library:
        blocks.append(np.arange(p0, p0 + t.X.shape[1]))
        p0 += t.X.shape[1]
    return SubsetLS(np.column_stack([t.X for t in library]), r0, blocks,
                    np.concatenate([t.lower for t in library]), np.concatenate([t.upper for t in library]), folds)


def _refine_tau(library, S: tuple, j: int, data: RigData, base, r0, groups) -> float:
    """Creep time constant [s] minimising the residual of the model ``S`` (bounded, in log tau)."""
    from scipy.optimize import minimize_scalar
    others = [library[i] for i in S if i != j]
    X0 = [t.X for t in others]
    lo = np.concatenate([t.lower for t in others] + [[0.0]])
    hi = np.concatenate([t.upper for t in others] + [[1.0]])

    def rss(log_tau):
        col = _demean(creep_term(data, base, float(np.exp(log_tau))).X, groups)
        X = np.column_stack(X0 + [col])
        nrm = np.maximum(np.linalg.norm(X, axis=0), 1e-300)
        res = lsq_linear(X / nrm, r0, bounds=(lo * nrm, hi * nrm), method="bvls")
        return float(((X / nrm) @ res.x - r0) @ ((X / nrm) @ res.x - r0))

    t0 = np.log(library[j].extra_tau)
    res = minimize_scalar(rss, bounds=(t0 - 0.5 * np.log(2), t0 + 0.5 * np.log(2)), method="bounded",
                          options={"xatol": 0.01})
    return float(np.exp(res.x))


def _alternatives(library, ls: SubsetLS, S: tuple, j: int, rss: float, sigma: float, n: int) -> list:
    """Terms of another effect that, put in place of term ``j``, fit within delta BIC 10: the data cannot
    tell them apart (e.g. creep with a time constant well below the hold time looks like a uniform scale)."""
    out = []
    rest = tuple(i for i in S if i != j)
    for i, u in enumerate(library):
        if u.effect == library[j].effect or i in S or not _compatible(library, rest, i):
            continue
        _, rss_alt = ls.fit(tuple(sorted(rest + (i,))))
        dbic = (rss_alt - rss) / sigma ** 2 + (u.n_params - library[j].n_params) * np.log(n)
        if dbic < DBIC_MIN:
            label = u.effect + (f" at {u.location}" if u.location else "")
            if u.effect == "creep":
                label += f" (tau {u.extra_tau:g} s)"
            out.append(label)
    return out


def _demean(a: np.ndarray, groups: np.ndarray) -> np.ndarray:
    """``a`` (n,) or (n, k) minus its mean within each group."""
    _, inv = np.unique(groups, return_inverse=True)
    cnt = np.bincount(inv).astype(float)
    a2 = a.reshape(a.shape[0], -1)
    means = np.stack([np.bincount(inv, weights=a2[:, j]) / cnt for j in range(a2.shape[1])], axis=1)
    return (a2 - means[inv]).reshape(a.shape)


def _within_hold_autocorrelation(data: RigData, resid: np.ndarray) -> float:
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


def _report_params(term: Term, val, se) -> tuple[dict, dict]:
    params, iv = {}, {}
    for name, v, s in zip(term.names, val, se):
        lo, hi = v - 1.96 * s, v + 1.96 * s
        if name == "r_minus_1":
            name, v, lo, hi = "r", 1 + v, 1 + lo, 1 + hi
        if name.endswith("_rad_per_Nmm"):
            name = name.replace("_rad_per_Nmm", "_rad_per_Nm")
            v, lo, hi = v * 1e3, lo * 1e3, hi * 1e3
        params[name] = float(v)
        iv[name] = [float(lo), float(hi)]
    if term.effect == "creep":
        params["tau_s"] = float(getattr(term, "extra_tau", np.nan))
    return params, iv
