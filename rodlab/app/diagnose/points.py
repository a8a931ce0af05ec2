"""Instrument-point residuals: where a calibrated model still misses, in the terms of the data at hand.

After ``rodlab calibrate --points`` the residuals (measured minus model, base and tool fitted) are tested
against the instrument's noise and then against candidate explanations, each a small linear model of the
residual vectors fitted by least squares and judged by an F-test of the sum of squares it removes:

- ``periodic_joint_error`` (per joint): first and second harmonics of the joint angle (gear eccentricity,
  encoder or transmission errors the geometric model cannot carry);
- ``lost_motion`` (per joint): the direction the joint was last moved from (backlash, hysteresis);
- ``drift``: a quadratic in each point's time (a ``time_s`` column) or else in measurement order (thermal growth,
  instrument drift);
- ``thermal_drift``: the arm's growth with each point's temperature (a ``temp_C`` column);
and the rms per workspace region (reach and height terciles) shows where the model is worst. A candidate is
a finding when it removes at least 5 % of the residual sum of squares with p < 1e-3; findings are taken
one at a time, each tested on what the previous ones leave (:func:`_greedy`).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rodlab.calibrate.crossval import joint_sweeps
from rodlab.calibrate.effects.thermal_drift import growth_lever_W
from rodlab.calibrate.kinematics import forward, harmonic_basis

__all__ = ["PointFinding", "PointsDiagnosis", "diagnose_points", "point_candidates", "FORMAT_POINTS_DIAGNOSIS"]

FORMAT_POINTS_DIAGNOSIS = "rodlab.points_diagnosis/1"
P_FINDING = 1e-3
MIN_SHARE = 0.05


@dataclass(frozen=True)
class PointFinding:
    """One explanation of the residuals: ``effect`` name, ``where`` (joint / data), the share of the residual
    sum of squares it removes, the F-test p-value, and what it means."""

    effect: str
    where: str
    explained_share: float
    p_value: float
    meaning: str


@dataclass(frozen=True)
class PointsDiagnosis:
    """The residual test and the findings of an instrument-point calibration.

    points; rms_mm : residual rms per coordinate [mm]; noise_mm : the instrument noise assumed [mm];
    reduced_chi2 : residual sum of squares / (noise^2 x degrees of freedom); findings : ranked by share;
    regions : (name, points, rms [mm]) per workspace region
    """

    points: int
    rms_mm: float
    noise_mm: float
    reduced_chi2: float
    findings: tuple
    regions: tuple = field(default=())

    @property
    def consistent(self) -> bool:
        """The residuals are what the stated noise explains (within a 30 % margin on the variance)."""
        return self.reduced_chi2 < 1.3 and not self.findings

    def summary(self) -> str:
        lines = [f"instrument points: {self.points} poses, residual rms {self.rms_mm * 1e3:.1f} um per coordinate "
                 f"against {self.noise_mm * 1e3:.1f} um of instrument noise (reduced chi-square "
                 f"{self.reduced_chi2:.1f} at that one level; the calibration's residual test weighs each point by "
                 f"its own sigma where the file states them)"]
        if not self.findings:
            lines.append("  no joint-, direction-, order- or temperature-dependent pattern stands out"
                         + ("" if self.consistent else "; the excess is spread over the workspace (the instrument "
                            "noisier than stated, or physics no candidate here describes: link or joint deflection "
                            "beyond the joints' springs, a tool that moved)"))
        for f in self.findings:
            lines.append(f"  {f.effect} ({f.where}): removes {f.explained_share:.0%} of the residual "
                         f"(p = {f.p_value:.1e}): {f.meaning}")
        if self.regions:
            worst = max(self.regions, key=lambda r: r[2])
            lines.append(f"  worst workspace region: {worst[0]} ({worst[1]} poses, rms {worst[2] * 1e3:.0f} um)")
        return "\n".join(lines)

    def to_dict(self) -> dict:
        return {"format": FORMAT_POINTS_DIAGNOSIS, "points": self.points, "residual_rms_mm": self.rms_mm,
                "noise_mm": self.noise_mm, "reduced_chi2": self.reduced_chi2, "consistent": self.consistent,
                "findings": [vars(f) for f in self.findings],
                "regions": [{"region": n, "points": k, "rms_mm": r} for n, k, r in self.regions]}


def _f_test(r: np.ndarray, X: np.ndarray) -> tuple[float, float]:
    """Share of ``sum r^2`` removed by the least-squares fit of ``r`` (3N,) by the columns of ``X`` (3N, k), and
    the F-test's p-value."""
    from scipy.stats import f as f_dist
    m, k = X.shape
    rss0 = float(r @ r)
    B, *_ = np.linalg.lstsq(X, r, rcond=None)
    e = r - X @ B
    rss1 = float(e @ e)
    dof = m - k
    if rss0 <= 0 or dof <= 0 or rss1 <= 0:
        return 0.0, 1.0
    F = ((rss0 - rss1) / k) / (rss1 / dof)
    return 1.0 - rss1 / rss0, float(f_dist.sf(F, k, dof))


def _approach(q: np.ndarray) -> np.ndarray:
    """+1 / -1: the direction each joint last moved in before each pose (0 before any move), shape=(N, n)."""
    step = np.sign(np.diff(q, axis=0, prepend=q[:1]))
    last = np.zeros_like(step)
    for i in range(len(q)):
        last[i] = np.where(step[i] != 0, step[i], last[i - 1] if i else 0.0)
    return last


def _joint_columns(params, q: np.ndarray) -> np.ndarray:
    """Motion of the measured point per radian of each joint, in the measurement frame, shape=(N, n, 3)."""
    fr = forward(params, q)
    col = np.cross(fr.z_prev, fr.p0[:, None, :] - fr.o_prev)
    return col @ fr.R_W0.T


def _through_joint(cols_j: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Design (3N, k): an angle error ``sum_k b_k f_k(q)`` of one joint seen at the point (``cols_j`` (N, 3))."""
    return (cols_j[:, :, None] * f[:, None, :]).reshape(-1, f.shape[1])


def point_candidates(q: np.ndarray, cols: np.ndarray, modelled=(), time_s=None):
    """(effect, where, design (3N, k), meaning) of every candidate explanation of the points' residuals, for joint
    angles ``q`` (N, n) [rad] and the joints' residual columns ``cols`` (N, n, 3) [mm/rad]; ``modelled``: joints
    whose periodic error the identification already carries (left out). Poses taken one joint at a time
    (:func:`~calibrate.crossval.joint_sweeps`) see a joint's periodic error in its own sweep only, where it cannot
    be told from whatever differs between the sweeps: named, not advised (a trial: following the advice made the
    held-out error worse). ``time_s`` (N,) each point's time [s] (NaN where not recorded) or None: the drift's
    axis where it was recorded (a pause between poses is then a pause), else the measurement order."""
    N, n = q.shape
    swept = joint_sweeps(q) is not None
    t, clock = _clock(time_s, N)
    yield ("drift", clock, np.kron(np.c_[t, t ** 2], np.eye(3)),
           ("the error changes with the time each pose was measured at (time_s)" if clock == "time" else
            "the error changes in the order the poses were measured") + ": thermal growth of the arm or "
           "instrument drift "
           "(re-measure a reference pose during the session), or, when one joint was swept at a time, whatever "
           "differs between the sweeps")
    approach = _approach(q)
    harmonics = harmonic_basis(q)                                  # (N, n, 4): the terms --joint-harmonics fits
    for j in range(n):
        if np.ptp(q[:, j]) < np.deg2rad(1.0):
            continue
        if j + 1 not in modelled:
            flag = ",".join(str(k) for k in sorted({*modelled, j + 1}))
            advice = (f"; the poses move one joint at a time, so it is seen in joint {j + 1}'s sweep only and cannot "
                      f"be told from what differs between the sweeps: measure varied poses (`rodlab plan`) before "
                      f"modelling it with --joint-harmonics" if swept else
                      f": model it with `rodlab calibrate --joint-harmonics {flag}`")
            yield ("periodic_joint_error", f"joint {j + 1}", _through_joint(cols[:, j], harmonics[:, j]),
                   f"an angle error periodic in joint {j + 1}'s angle (gear eccentricity, encoder or transmission "
                   f"error) that the geometric model cannot carry{advice}")
        a = approach[:, j]
        if (a > 0).sum() >= 3 and (a < 0).sum() >= 3:
            yield ("lost_motion", f"joint {j + 1}", _through_joint(cols[:, j], a[:, None]),
                   f"joint {j + 1}'s angle error depends on the direction it was approached from (backlash, lost "
                   "motion); approach every pose from the same side")


#: a points file's temperature column must span this much [K] for its thermal growth to be tested
THERMAL_SPAN_K = 0.2
#: a time or temperature column is used where at least this share of its cells were recorded (the rest
#: interpolated between their neighbours in measurement order)
RECORDED_SHARE = 0.8


def _filled(values) -> tuple[np.ndarray | None, int]:
    """A per-point column with its blank (NaN) cells interpolated linearly between their recorded neighbours in
    measurement order (held at the end values beyond them), and how many were filled; (None, 0) where fewer than
    :data:`RECORDED_SHARE` of the cells, or fewer than three, were recorded."""
    if values is None:
        return None, 0
    v = np.asarray(values, float)
    ok = np.isfinite(v)
    if ok.sum() < max(3, RECORDED_SHARE * v.size):
        return None, 0
    at = np.arange(v.size)
    return np.interp(at, at[ok], v[ok]), int((~ok).sum())


def _clock(time_s, N: int) -> tuple[np.ndarray, str]:
    """The drift's axis scaled to [-1, 1] and its name: each point's time where recorded and spanning a time,
    else the measurement order."""
    t, _ = _filled(time_s)
    if t is None or np.ptp(t) <= 0:
        return np.linspace(-1.0, 1.0, N), "measurement order"
    return 2.0 * (t - t.min()) / np.ptp(t) - 1.0, "time"


def _thermal_candidate(params, q: np.ndarray, temp_C) -> list:
    """The arm growing with the temperature of each point (a ``temp_C`` column): every point moved away from the
    base by ``growth x (T - mean T)`` of its distance (links of steel or aluminium: 12-23 ppm/K), seen in the
    instrument's frame; none without a column spanning :data:`THERMAL_SPAN_K` (a trial: the UR10's raw data had a
    temperature per point and the points format had refused it). Blank cells are interpolated between their
    neighbours (a trial: one blank cell had refused the whole file)."""
    T, filled = _filled(temp_C)
    if T is None or np.ptp(T) < THERMAL_SPAN_K:
        return []
    dT = T - float(np.mean(T))
    X = (growth_lever_W(forward(params, q), 1.0) * dT[:, None]).reshape(-1, 1)     # the campaign effect's lever
    gaps = f"; {filled} blank temp_C cell(s) interpolated between their neighbours" if filled else ""
    return [("thermal_drift", "temperature", X,
             f"the arm grows with the temperature ({np.ptp(T):.1f} K over the points{gaps}): its links expand away "
             f"from the base; calibrate at the working temperature, or measure a reference pose as it warms up")]


def _greedy(r: np.ndarray, candidates: list) -> list:
    """Findings one at a time: the candidate that removes most of what is left, tested on what is left, then
    removed, so that two names for one pattern are not both reported. Shares are of the original residual."""
    total, findings, X_all = float(r @ r), [], np.zeros((r.size, 0))
    while candidates:
        rest = r - X_all @ np.linalg.lstsq(X_all, r, rcond=None)[0] if X_all.shape[1] else r
        tests = [_f_test(rest, c[2]) for c in candidates]
        k = int(np.argmax([t[0] for t in tests]))
        (share, p), best = tests[k], candidates[k]
        if not (p < P_FINDING and share * float(rest @ rest) / total >= MIN_SHARE):
            break
        effect, where, X, meaning = best
        findings.append(PointFinding(effect, where, share * float(rest @ rest) / total, p, meaning))
        X_all = np.c_[X_all, X]
        del candidates[k]
    return findings


def _regions(p0: np.ndarray, r: np.ndarray) -> tuple:
    """Rms per tercile of reach (distance from the base axis) and of height."""
    out = []
    for name, v in (("reach", np.hypot(p0[:, 0], p0[:, 1])), ("height", p0[:, 2])):
        edges = np.quantile(v, [1 / 3, 2 / 3])
        for label, m in (("low", v <= edges[0]), ("middle", (v > edges[0]) & (v <= edges[1])), ("high", v > edges[1])):
            if m.sum() >= 3:
                out.append((f"{name} {label} ({v[m].min():.0f}-{v[m].max():.0f} mm)", int(m.sum()),
                            float(np.sqrt(np.mean(r[m] ** 2)))))
    return tuple(out)


def diagnose_points(robot, pts, res, noise_mm: float) -> PointsDiagnosis:
    """The diagnosis of ``res`` (an identification of the instrument points ``pts``) under ``noise_mm``."""
    r = np.asarray(res.residuals_mm, float).reshape(-1, 3)
    q = np.deg2rad(np.asarray(pts.q_deg, float))
    modelled = tuple(res.harmonic_range_deg)
    candidates = list(point_candidates(q, _joint_columns(res.params, q), modelled, pts.time_each_s))
    candidates += _thermal_candidate(res.params, q, pts.temp_each_C)
    findings = _greedy(r.ravel(), candidates)
    dof = max(r.size - len(res.free), 1)
    p0 = forward(res.params, q).p0
    return PointsDiagnosis(len(r), float(np.sqrt(np.mean(r ** 2))), float(noise_mm),
                           float(np.sum(r ** 2) / (noise_mm ** 2 * dof)), tuple(findings), _regions(p0, r))
