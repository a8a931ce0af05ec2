"""Judge a recording's linear compliance against the simulation's envelope (:mod:`.envelope`).

The difference d = C_meas - C_sim over the measured entries has, if the rod is the design within tolerance, the
covariance S = (tolerances through the sensitivities) + (the method's accuracy) + (the measurement's own). With
the tolerances integrated out this way:

- inside the envelope (chi-square of d under S with p > 1e-3), the finding is ``model_form`` (effects v2): the
  rod as built, with its r_mn (paper Eq. 20, entry by entry) and the as-built keys that explain them (their
  posterior mean given d); no local cause is named, and the finding says how large a compliant joint would have
  to be to stand out, and how much a coupon test and a solid FEA would lower that;
- outside, a local cause (a compliant joint at a place, torsion of pipe I, a uniform scale beyond the material's
  spread) is named when its likelihood ratio against the envelope is significant (p <= 1e-3, the diagnosers'
  rule); places that fit within 10 of the best are named as a group; what none explains is ``unexplained`` at
  ``C_F``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import lsq_linear

from rodlab.enums import MODEL_FORM
from rodlab.hypothesis import Hypothesis
from rodlab.sensitivity import METHOD_ACCURACY

from .chi2 import chi2_sf
from .criteria import DBIC_MIN, P_MAX
from .envelope import Envelope
from .report import Finding
from .rig_linear import LinearPart

__all__ = ["judge_linear", "FormJudgement"]

#: a coupon test of the laminate measures E and G to about this (relative standard deviation)
COUPON_RELATIVE = 0.02
#: an as-built key is reported when the recording shrinks its standard deviation below this share of the prior's
INFORMED = 0.9


@dataclass
class FormJudgement:
    """The linear part judged against the envelope.

    findings : ``model_form``, a located cause, ``unexplained`` at ``C_F`` (in that order of strength);
    chi2 : d^T S^-1 d; dof : entries; p : its chi-square p-value; chi2_noise : d^T V^-1 d (the measurement alone)
    """

    findings: list
    chi2: float
    dof: int
    p: float
    chi2_noise: float

    def to_dict(self) -> dict:
        return {"envelope_chi2": self.chi2, "envelope_dof": self.dof, "envelope_p": self.p,
                "measurement_chi2": self.chi2_noise}


class _Whitened:
    """d and pattern columns whitened by the envelope covariance S (Cholesky)."""

    def __init__(self, d: np.ndarray, S: np.ndarray) -> None:
        self.Linv = np.linalg.inv(np.linalg.cholesky(S + 1e-30 * np.eye(len(d))))
        self.z = self.Linv @ d
        self.q0 = float(self.z @ self.z)

    def fit(self, B: np.ndarray, lower, upper) -> tuple[np.ndarray, np.ndarray, float]:
        """Bounded GLS of d on the columns B: (coefficients, standard errors, chi-square drop)."""
        A = self.Linv @ B
        res = lsq_linear(A, self.z, bounds=(lower, upper), method="bvls")
        r = self.z - A @ res.x
        se = np.sqrt(np.clip(np.diag(np.linalg.pinv(A.T @ A)), 0, None))
        return res.x, se, self.q0 - float(r @ r)


def _patterns(h: Hypothesis, entries) -> np.ndarray:
    return np.array([[dC[m, n] for dC in h.dC] for m, n in entries])


def judge_linear(linear: LinearPart, env: Envelope, causes: list, rms: tuple) -> FormJudgement:
    """``linear`` against ``env``; ``causes``: structural hypotheses (with ``dC``) that may explain a difference
    outside the envelope; ``rms``: (before, after) of the readings against the simulation and the linear part."""
    E = linear.entries
    d = linear.C - np.array([env.C_sim[m, n] for m, n in E])
    S = env.covariance(E) + linear.cov
    w = _Whitened(d, S)
    qv = float(d @ np.linalg.pinv(linear.cov) @ d)
    p0 = chi2_sf(w.q0, len(E))
    out = FormJudgement([], w.q0, len(E), p0, qv)
    if p0 >= P_MAX:
        if chi2_sf(qv, len(E)) < P_MAX:
            out.findings.append(_model_form(linear, env, d, S, causes, rms, out))
        return out
    scored = sorted(((w.fit(_patterns(h, E), h.lower, h.upper), h) for h in causes), key=lambda t: -t[0][2])
    if scored and chi2_sf(scored[0][0][2], scored[0][1].n_params) <= P_MAX:
        (val, se, lr), h = scored[0]
        out.findings.append(_cause(h, val, se, lr, scored, rms, w.q0, len(E)))
        rest = d - _patterns(h, E) @ val
        q1 = w.q0 - lr
        if chi2_sf(q1, max(len(E) - h.X.shape[1], 1)) < P_MAX:
            out.findings.append(_outside(q1, len(E), rms, "beside the named cause"))
        else:
            out.findings.append(_model_form(linear, env, rest, S, [], rms, out))
        return out
    out.findings.append(_outside(w.q0, len(E), rms, "and no local cause (joint, torsion, scale) explains it"))
    return out


def _cause(h: Hypothesis, val, se, lr: float, scored, rms, q0: float, k: int) -> Finding:
    """A local cause outside the envelope: its parameters, the places that fit within delta 10."""
    params, intervals = h.reported(val, se)
    group = [g.location for (_, _, l2), g in scored[1:] if g.effect == h.effect and g.location
             and lr - l2 < DBIC_MIN]
    location = "|".join([h.location] + group) if h.location and group else h.location
    ev = {"lr_chi2": float(lr), "lr_p": chi2_sf(lr, h.n_params), "envelope_chi2_before": q0,
          "envelope_chi2_after": q0 - lr, "envelope_dof": k, "beyond_tolerance": True}
    alts = [g.label for (_, _, l2), g in scored[1:] if g.effect != h.effect and lr - l2 < DBIC_MIN]
    if alts:
        ev["alternatives"] = alts
    if group:
        ev["separate_by"] = ("load along x_T with the x gauge (pipe I bending) and along y_T (torsion): the lever "
                             "from each place to the ball differs in each")
    text = (h.explanation + "; beyond what the design's tolerances and the simulation's accuracy explain "
            f"(envelope chi-square {q0:.1f} on {k} entries -> {q0 - lr:.1f})")
    return Finding(h.effect, location, text, params, intervals, rms[0], rms[1], ev)


def _outside(q: float, k: int, rms, why: str) -> Finding:
    return Finding("unexplained", "C_F", f"the measured linear compliance lies outside the design's envelope "
                   f"(chi-square {q:.1f} on {k} entries) {why}: a difference of form that no tolerance, method error "
                   "or modelled local cause produces", {"envelope_chi2": q}, {}, rms[0], rms[1],
                   {"envelope_chi2": q, "envelope_dof": k})


def _model_form(linear: LinearPart, env: Envelope, d, S, causes, rms, judged: FormJudgement) -> Finding:
    """``model_form``: r_mn and the as-built keys (posterior given d), and the joint size that would stand out."""
    E = linear.entries
    params, intervals = {}, {}
    sim = np.array([env.C_sim[m, n] for m, n in E])
    for (m, n), c, s, cs in zip(E, linear.C, linear.sd(), sim):
        name = f"r_{m + 1}{n + 1}"
        params[name] = float(c / cs)
        intervals[name] = sorted([float((c - 1.96 * s) / cs), float((c + 1.96 * s) / cs)])
    if env.params:
        P = np.diag(env.prior_sd() ** 2)
        J = env.jacobian(E)
        K = P @ J.T @ np.linalg.inv(S)
        mean, cov = K @ d, P - K @ J @ P
        unresolved = []
        for p, mu, var in zip(env.params, mean, np.diag(cov)):
            sd = float(np.sqrt(max(var, 0.0)))
            if sd > INFORMED * p.sigma:             # the recording says nothing about this key
                unresolved.append(p.key)
                continue
            params[p.key] = float(p.nominal + mu)
            intervals[p.key] = [float(p.nominal + mu - 1.96 * sd), float(p.nominal + mu + 1.96 * sd)]
    ev = dict(judged.to_dict(), resolve=_resolution(env, E, S, linear, d, causes), envelope=env.source)
    if env.params:
        ev["keys_not_resolved"] = unresolved
    text = ("consistent with the design within tolerance: the rod as built differs from the simulated design by no "
            "more than its tolerances and the simulation method's accuracy explain; r_mn = measured / simulated, "
            "entry by entry (paper Eq. 20)" + ("; the as-built keys the recording resolves" if len(params) > len(E)
                                                else ""))
    return Finding(MODEL_FORM, None, text, params, intervals, rms[0], rms[1], ev)


def _resolution(env: Envelope, E, S, linear: LinearPart, d, causes) -> list:
    """For each joint place: the bending compliance that would stand out against this envelope (chi-square 10.8,
    p = 1e-3), the best fit here, and the same limit with the moduli measured by a coupon test and a solid FEA."""
    tight = env.tightened(COUPON_RELATIVE, METHOD_ACCURACY["solid"]) if env.params else None
    out = []
    for h in causes:
        if h.effect != "joint_compliance":
            continue
        b = _patterns(h, E)[:, 0]
        info = float(b @ np.linalg.solve(S, b))
        est = float(b @ np.linalg.solve(S, d)) / info if info > 0 else 0.0
        row = {"place": h.location, "detectable_s_bend_rad_per_Nm": _limit(info) * h.report_scale[0],
               "best_fit_s_bend_rad_per_Nm": est * h.report_scale[0],
               "sd_s_bend_rad_per_Nm": h.report_scale[0] / np.sqrt(info) if info > 0 else float("inf")}
        if tight is not None:
            St = tight.covariance(E) + linear.cov
            row["detectable_with_coupon_and_solid_fea"] = _limit(float(b @ np.linalg.solve(St, b))) * h.report_scale[0]
        out.append(row)
    return out


def _limit(info: float) -> float:
    """The smallest spring whose chi-square against the envelope reaches 10.83 (p = 1e-3, one parameter)."""
    return float(np.sqrt(10.83 / info)) if info > 0 else float("inf")
