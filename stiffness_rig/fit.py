"""Load-deflection fitting (paper Section 4.2, Eqs. 20-22): measured C_F, r_rod, the measured compliance file.

For every load axis and measured displacement component the hold averages are fitted with one slope and
an intercept per branch (loading / unloading): Coulomb friction in the rig's slides shifts the two
branches apart but leaves the slope (the compliance) alone. Separate per-branch lines are reported too,
with their intercepts on the load axis in kg (the paper's ~0.1 kg). ``robust=True`` uses a soft-L1 loss
(outlying holds lose weight). Standard errors come from the residual scatter of the hold averages.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from rodlab import __version__
from rodlab.core.compliance import RodCompliance, r_mn as eq20_r_mn, r_rod as eq21_r_rod
from rodlab.core.enums import LoadAxis, Method, Phase
from rodlab.core.fileio import sha256_file
from rodlab.core.units import G0

from .completion import complete_c_f
from .errors import NoLoadResponse, RigError
from .creep_check import creep_within_holds
from .gross import without_gross
from .fit_checks import (check_load_response, dead_load_warnings, direction_warnings, gauge_scale_problems,
                         inverse_variance_mean, lack_of_fit_warnings, load_drift_warnings, load_scale_problems,
                         reciprocity_problems, structural_zero_warnings)
from .glitches import without_glitches
from .holds import Holds, hold_averages
from .load import LoadCheck, measured_load, zero_offset
from .r_rod_checks import PLAUSIBLE_R_ROD, r_rod_caution, r_rod_note
from .recording import RigRecording
from .settling import missing_holds_text, settled
from .zero_load import reference_level, zero_load_se

__all__ = ["LineFit", "RigFit", "fit_recording", "NoLoadResponse", "r_rod_caution", "r_rod_note", "PLAUSIBLE_R_ROD",
           "noise_text"]

_AX = "xyz"


@dataclass
class LineFit:
    """Fit of one displacement component against the load along one axis.

    slope_mm_per_N : common slope (= C_F[component, axis]); se_mm_per_N : its standard error
    intercept_mm : {"load": a, "unload": a} of the common-slope model
    branch : per-branch independent lines {phase: {"slope_mm_per_N", "intercept_mm", "zero_load_kg"}}
    zero_load_kg : {phase: mass where the common-slope line passes the unloaded reference hold's reading (zero
        displacement without one)} (NaN if slope ~ 0);
        zero_load_se_kg : {phase: its standard error} [kg] (delta method on the intercept and the slope)
    residual_rms_mm, n_holds : fit quality
    unloaded_apart : the holds without a hanger lie off both branch lines (friction that lets go at mass 0, or a
        dead load missing from ``mass_kg``): they were given a level of their own and do not bear on the slope
    dead_load_kg : (low, high) the load [kg] missing from ``mass_kg`` whenever the hanger is on that puts the unloaded
        holds where they are, from the loading and the unloading branch (a hanger or loading frame not logged; friction
        in the rig puts the two apart); None where they are not apart that way
    """

    axis: LoadAxis
    component: int
    slope_mm_per_N: float
    se_mm_per_N: float
    intercept_mm: dict
    zero_load_kg: dict
    branch: dict
    residual_rms_mm: float
    n_holds: int
    unloaded_apart: bool = False
    dead_load_kg: tuple | None = None
    zero_load_se_kg: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"load_axis": str(self.axis), "component": _AX[self.component],
                "slope_mm_per_N": self.slope_mm_per_N, "se_mm_per_N": self.se_mm_per_N,
                "intercept_mm": self.intercept_mm, "zero_load_kg": self.zero_load_kg, "branch": self.branch,
                "residual_rms_mm": self.residual_rms_mm, "n_holds": self.n_holds,
                "unloaded_apart": self.unloaded_apart, "zero_load_se_kg": self.zero_load_se_kg,
                "dead_load_kg": None if self.dead_load_kg is None else list(self.dead_load_kg)}


@dataclass
class RigFit:
    """Result of fitting a recording (scipy-``OptimizeResult`` style).

    C_F_meas : measured entries [mm/N], shape=(3, 3), NaN where not measured; C_F_se : their standard errors
    lines : every :class:`LineFit`; noise_mm : within-hold noise of one reading; holds : the hold table
    r_rod : Eq. 21 (None without a simulated compliance); success, message : whether the fit can be used;
    warnings : what the fit checked in itself and a user must know (:mod:`.fit_checks`: reciprocity, lack of fit)
    load : nominal (mass x g0) against measured load per hold and branch (:class:`LoadCheck`), None without a
    load cell; with one, the lines are fitted against the measured load
    """

    C_F_meas: np.ndarray
    C_F_se: np.ndarray
    lines: list
    noise_mm: float
    holds: Holds
    r_rod: float | None = None
    success: bool = True
    message: str = ""
    residuals_mm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    load: LoadCheck | None = None
    warnings: list = field(default_factory=list)

    def compliance(self, sim: RodCompliance, recording: RigRecording | None = None) -> RodCompliance:
        """The measured compliance file: measured C_F (symmetrised; unmeasured entries r_rod x simulated, an
        unmeasured diagonal entry raised where the measured entries need more: :mod:`.completion`, said in the
        provenance's ``warnings``),
        C_g = r_rod x C_g_sim (Eq. 22), mass / COM / tool of the simulated file; the per-entry factors r_mn
        (Eq. 20) and the standard errors of the measured entries (``C_F_sigma``), NaN where not measured."""
        r = self.r_rod if self.r_rod is not None else eq21(self, sim)
        M = self.C_F_meas
        source = str(recording.path) if recording is not None and recording.path is not None else ""
        C, notes = complete_c_f(M, r * sim.C_F, source)
        notes = [n + "; or let `rodlab diagnose --rig` find the joint and predict it (--design, --export)" for n in notes]
        prov = {"rodlab_version": __version__, "method": "meas", "generator": "rodlab rig fit",
                "simulated": {"method": str(sim.method), "C_F_mm_per_N": sim.C_F.tolist(),
                              "provenance": sim.provenance},
                "noise_mm": self.noise_mm, "lines": [ln.to_dict() for ln in self.lines],
                "measured_entries": [[bool(np.isfinite(v)) for v in row] for row in M],
                "C_F_se_mm_per_N": np.where(np.isfinite(self.C_F_se), self.C_F_se, -1.0).tolist(),
                "unmeasured_entries": "r_rod x simulated" + ("; a diagonal one raised to the least the measured "
                                                             "entries allow (warnings)" if notes else ""),
                "load": "force_N (load cell)" if self.load is not None else "mass_kg x g0",
                "warnings": list(self.warnings) + notes}
        if self.load is not None:
            prov["measured_load"] = self.load.to_dict()
        if recording is not None and recording.path is not None:
            prov["recording"] = str(recording.path)
            prov["recording_sha256"] = sha256_file(recording.path)
        return RodCompliance(sim.rod, Method.MEAS, C, r * sim.C_g, sim.mass_kg, sim.com_T_mm, sim.tool_mm, r, prov,
                             r_mn=self.r_mn(sim), C_F_sigma=np.where(np.isfinite(M), self.C_F_se, np.nan))

    def r_mn(self, sim: RodCompliance) -> np.ndarray:
        """Per-entry correction factors (paper Eq. 20) measured / simulated [-], shape=(3, 3); NaN where the
        entry was not measured or the simulated entry is 0."""
        return eq20_r_mn(self.C_F_meas, sim.C_F)


def eq21(fit: RigFit, sim: RodCompliance) -> float:
    M = fit.C_F_meas
    if not (np.isfinite(M[1, 1]) and np.isfinite(M[2, 2])):
        missing = [n for n, v in (("c22 (load y, measure y)", M[1, 1]), ("c33 (load z, measure z)", M[2, 2]))
                   if not np.isfinite(v)]
        raise RigError(f"r_rod (Eq. 21) needs c22 and c33; the recording lacks {' and '.join(missing)}",
                       key="load_axis")
    return eq21_r_rod(M, sim.C_F)


def _lsq(X, y, robust: bool, f_scale: float):
    if not robust:
        coef, *_ = np.linalg.lstsq(X, y, rcond=None)
        return coef
    from scipy.optimize import least_squares
    c0, *_ = np.linalg.lstsq(X, y, rcond=None)
    r = least_squares(lambda c: X @ c - y, c0, loss="soft_l1", f_scale=max(f_scale, 1e-9))
    return r.x


def _creep_text(rec: RigRecording) -> list[str]:
    found = creep_within_holds(rec)
    return [] if found is None else [found.text()]


def fit_recording(rec: RigRecording, sim: RodCompliance | None = None, robust: bool = False) -> RigFit:
    """Fit every (load axis, measured component) of ``rec``; Eq. 21 when ``sim`` is given. Each hold's
    settling (an acquired recording's samples before its ``hold_s x rate_Hz``, or the first seconds where the
    readings show one: :mod:`.settling`, as the diagnosis) and single readings far off their hold's line
    (:mod:`.glitches`) are left out, with a warning but for an acquired recording's settling."""
    missing = missing_holds_text(rec)
    rec, gross = without_gross(rec)
    cut = settled(rec)
    rec, glitched = without_glitches(cut.recording)
    glitched = (([missing] if missing else []) + ([gross.text()] if gross.any else [])
                + ([cut.text()] if cut.dropped and (cut.per_hold is None or cut.incomplete) else []) + glitched)
    holds = hold_averages(rec)
    noise = holds.noise_mm()
    lines, resid_all = [], []
    reference = _reference_holds(holds)
    cell = _without_cell_offset(holds)         # the loads of the lines: the load cell's zero offset taken off
    for axis in sorted(set(holds.axis), key=lambda a: a.value):
        on_axis = np.array([a is axis for a in holds.axis])
        h = cell.select(on_axis & ~reference)
        for c in range(3):
            fitted = _fit_line(h, axis, c, robust, noise, reference_level(holds, on_axis & reference, c, noise))
            if fitted is not None:
                lines.append(fitted[0])
                resid_all.append(fitted[1])
    if not lines:
        raise RigError("no load axis has a measured component with at least 3 holds at different loads",
                       path=rec.path, key="mass_kg")
    check_load_response(lines, rec, holds)
    M, S = _combine_lines(lines)
    fit = RigFit(M, S, lines, noise, holds, residuals_mm=np.concatenate(resid_all), load=measured_load(holds))
    refuse, warn = reciprocity_problems(M, S)
    warn += direction_warnings(lines)
    refuse += gauge_scale_problems(M, sim.C_F) if sim is not None else []
    warn += structural_zero_warnings(M, S, sim.C_F) if sim is not None else []
    scale_refuse, scale_warn = load_scale_problems(fit.load)
    refuse += scale_refuse
    warn += scale_warn
    fit.warnings = (refuse + warn + glitched + lack_of_fit_warnings(lines, holds, noise)
                    + load_drift_warnings(fit.load) + _creep_text(rec)
                    + dead_load_warnings(lines))
    if refuse:
        fit.success, fit.message = False, "; ".join(refuse) + "; nothing was written"
    if sim is not None:
        try:
            fit.r_rod = eq21(fit, sim)
        except RigError as e:            # after a refusal of the checks, its message first
            fit.message = "; ".join(m for m in (fit.message, e.detail) if m)
            fit.success = False
        else:
            if fit.success:
                _check_plausible_r_rod(fit, rec, sim)
    if fit.success:
        fit.message = f"{len(lines)} lines fitted; {noise_text(noise)}"
    elif fit.message.count("nothing was written") > 1:
        fit.message = fit.message.replace("; nothing was written", "", 1)
    return fit


def _check_plausible_r_rod(fit: "RigFit", rec: RigRecording, sim) -> None:
    """An r_rod no rod has against its own simulation makes the fit unusable (:func:`r_rod_caution`)."""
    caution = r_rod_caution(fit.r_rod, rec.rod, sim.rod)
    if caution:
        fit.success, fit.message = False, caution + "; nothing was written"


def noise_text(noise_mm: float) -> str:
    """The within-hold noise of one reading for a message: its value, or why there is none (1 reading per hold)."""
    if np.isfinite(noise_mm):
        return f"noise {noise_mm * 1e3:.2f} um per reading"
    return "noise not measurable within the holds (one reading each; `rodlab diagnose --rig` uses the repeats)"


def _without_cell_offset(holds: Holds) -> Holds:
    """``holds`` with the load cell's zero offset (:func:`~.load.zero_offset`) taken off its readings: the lines'
    slopes do not depend on it, their zero-load crossings do (an instrument trial: a 0.35 N offset had read as a
    +36 g crossing, a dead load that was not there)."""
    if not holds.has_force:
        return holds
    zero = zero_offset(holds)
    return dataclasses.replace(holds, force_N=holds.force_N - zero) if zero else holds


def _reference_holds(holds) -> np.ndarray:
    """The first hold of each series when it is at mass 0 (no hanger): the zero reference of the series. It
    carries no information on the slope, and no friction is engaged there, so it is not a point of either
    branch."""
    first = {}
    for i, a in enumerate(holds.axis):
        first.setdefault(a, i)
    reference = np.zeros(len(holds), dtype=bool)
    for a, i in first.items():
        reference[i] = holds.mass_kg[i] == 0.0
    return reference


def _fit_line(h, axis, c: int, robust: bool, noise: float, level: tuple[float, float] = (0.0, 0.0)):
    """The load-deflection line of component ``c`` of the holds ``h`` of one load axis (one intercept per
    branch when both load and unload holds exist), and its residuals [mm]; None with < 3 usable holds. The
    zero-load crossings are the loads where the lines pass ``level`` (the unloaded reference reading [mm] and its
    variance: :func:`_reference_level`)."""
    F = h.load_N() * axis.sign               # force component along the axis index [N] (load cell or mass x g0)
    is_unload = np.array([p is Phase.UNLOAD for p in h.phase])
    y = h.mean_mm[:, c]
    ok = np.isfinite(y)
    if ok.sum() < 3 or np.ptp(F[ok]) <= 0:
        return None
    Fo, yo, uo = F[ok], y[ok], is_unload[ok]
    two = uo.any() and (~uo).any()
    X = np.column_stack([~uo, uo, Fo]).astype(float) if two else np.column_stack([np.ones_like(Fo), Fo])
    coef = _lsq(X, yo, robust, 3 * noise if np.isfinite(noise) else 1e-3)
    res = yo - X @ coef
    apart = _unloaded_apart(X, yo, h.mass_kg[ok] == 0.0, Fo)
    dead_load = None
    if apart is not None:
        X = apart
        coef = _lsq(X, yo, robust, 3 * noise if np.isfinite(noise) else 1e-3)
        res = yo - X @ coef
        if _dead_load_missing(coef, np.sign(np.mean(Fo[h.mass_kg[ok] != 0.0]))):
            kg = (coef[:-2] - coef[-2]) / (coef[-1] * G0 * axis.sign)
            dead_load = (float(kg.min()), float(kg.max()))
    dof = max(len(yo) - X.shape[1], 1)
    s2 = float(res @ res / dof)
    cov = s2 * np.linalg.pinv(X.T @ X)
    slope, se = float(coef[-1]), float(np.sqrt(cov[-1, -1]))
    icpt = {"load": float(coef[0]), "unload": float(coef[1]) if two else float(coef[0])}
    significant = abs(slope) > 3 * se and abs(slope) > 0
    y0, var0 = level
    zero = {k: (float(-(v - y0) / (slope * G0 * axis.sign)) if significant else float("nan")) for k, v in icpt.items()}
    zero_se = {k: zero_load_se(coef, cov, i, axis.sign, y0, var0) if significant else float("nan")
               for k, i in (("load", 0), ("unload", 1 if two else 0))}
    branch = {}
    for name, m in (("load", ~uo), ("unload", uo)):
        if m.sum() >= 2 and np.ptp(Fo[m]) > 0:
            b, a = np.polyfit(Fo[m], yo[m], 1)
            branch[name] = {"slope_mm_per_N": float(b), "intercept_mm": float(a),
                            "zero_load_kg": float(-(a - y0) / (b * G0 * axis.sign)) if significant else float("nan")}
    return LineFit(axis, c, slope, se, icpt, zero, branch, float(np.sqrt(np.mean(res ** 2))), len(yo),
                   unloaded_apart=apart is not None, dead_load_kg=dead_load, zero_load_se_kg=zero_se), res


#: the holds without a hanger get a level of their own when that lowers the lines' residual this significantly
UNLOADED_APART_P = 1e-3


def _unloaded_apart(X: np.ndarray, y: np.ndarray, unloaded: np.ndarray, F: np.ndarray):
    """The design matrix with the holds at mass 0 on a level of their own (their own intercept: they no longer
    bear on the slope), or None. Used where the unloaded holds lie off the loaded lines beyond chance (F-test of
    the same least squares, p below :data:`UNLOADED_APART_P`) in one of two patterns: friction that lets go when
    the hanger is taken off (both branches apart, their intercepts more than 5 standard errors apart, the unloaded
    holds between them: new-user trial, c22 +5 % with 1 N friction), or a dead load missing from ``mass_kg``
    whenever the hanger is on (a hanger or loading frame not logged: every loaded hold sits one slope times that
    load beyond the unloaded level, which lies on the side of less load than every branch: new-user trial, r_rod
    1.696 for 1.600 with a 120 g hanger). Needs two loads besides; both models are refitted by least squares (the
    line's own fit may be robust)."""
    loaded = ~unloaded
    if not unloaded.any() or loaded.sum() < X.shape[1] + 1 or np.unique(F[loaded]).size < 2:
        return None
    X2 = np.column_stack([X[:, :-1] * loaded[:, None], unloaded.astype(float), X[:, -1]])
    if np.linalg.matrix_rank(X2) < X2.shape[1]:
        return None
    coef1, rss1 = _ols(X, y)
    coef2, rss2 = _ols(X2, y)
    dof2 = len(y) - X2.shape[1]
    if dof2 < 1 or rss1 <= rss2:
        return None
    cov = rss2 / dof2 * np.linalg.pinv(X2.T @ X2)
    if not (_friction_lets_go(coef2, cov) or _dead_load_missing(coef2, np.sign(np.mean(F[loaded])))):
        return None
    from scipy.special import fdtrc        # the F distribution's survival function (scipy.stats takes ~0.6 s)
    stat = (rss1 - rss2) / max(rss2 / dof2, 1e-300)
    return X2 if fdtrc(1, dof2, stat) < UNLOADED_APART_P else None


def _friction_lets_go(coef2: np.ndarray, cov: np.ndarray) -> bool:
    """Two branches apart (> 5 standard errors) with the unloaded level between them."""
    if coef2.size != 4:
        return False
    split, split_se = coef2[1] - coef2[0], np.sqrt(max(cov[0, 0] + cov[1, 1] - 2 * cov[0, 1], 0.0))
    between = min(coef2[0], coef2[1]) <= coef2[2] <= max(coef2[0], coef2[1])
    return bool(between and abs(split) > 5 * split_se)


def _dead_load_missing(coef2: np.ndarray, load_sign: float) -> bool:
    """Every branch's intercept beyond the unloaded level as a load of the loads' sign ``load_sign`` would put it:
    a load the log leaves out."""
    branches, level, slope = coef2[:-2], coef2[-2], coef2[-1]
    return bool(slope != 0 and np.all((branches - level) * np.sign(slope) * load_sign > 0))


def _ols(X: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, float]:
    coef = np.linalg.lstsq(X, y, rcond=None)[0]
    return coef, float(np.sum((y - X @ coef) ** 2))


def _combine_lines(lines: list) -> tuple[np.ndarray, np.ndarray]:
    """The measured compliance matrix [mm/N] and its standard errors, shape=(3, 3) (NaN where not measured):
    the inverse-variance mean of the slopes of every line of the same (component, load axis index), its standard
    error scaled by the lines' own scatter where that exceeds their standard errors (the Birge ratio
    sqrt(chi2 / dof) when above 1: lines of y and -y 8 % apart are no 0.002 % measurement)."""
    acc: dict[tuple[int, int], list] = {}
    for ln in lines:
        acc.setdefault((ln.component, ln.axis.index), []).append((ln.slope_mm_per_N, ln.se_mm_per_N))
    M = np.full((3, 3), np.nan)
    S = np.full((3, 3), np.nan)
    for (c, i), vals in acc.items():
        M[c, i], se, chi2 = inverse_variance_mean([s for s, _ in vals], [se for _, se in vals])
        birge = np.sqrt(chi2 / (len(vals) - 1)) if len(vals) > 1 else 1.0
        S[c, i] = float(max(birge, 1.0) * se)
    return M, S
