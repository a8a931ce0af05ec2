"""Diagnosis of a MultiCal campaign: residuals of the identified model against physics left out.

The identification's residuals r and Jacobian J are augmented with the columns H of each hypothesis; the
gain is the part of r that H explains beyond what the identified parameters already absorb (the
projection on the complement of J). Selection by the diagnosers' one routine (:mod:`.search`) under the
acceptance rule the rig diagnosis uses (:mod:`.criteria`: delta BIC <= -10 with the known device noise,
likelihood-ratio p <= 1e-3, leave-one-point-out cross-validation, a detection limit), then the campaign is
identified again with the found physics (freed fixture offsets, rescaled rod compliance, dropped outliers,
joint angles corrected by the fitted periodic errors — also at the validation points, as a controller would —,
by backlash or a non-linear spring, and measured points referred back to the campaign start for thermal growth;
:mod:`.campaign_refit`) to show the fit
(and, with validation points, the positioning error) improve.

Hypotheses come from the campaign effect registry (:data:`rodlab.calibrate.effects.CAMPAIGN_EFFECTS`, one
module per effect of ``contract/effects.md``, subject ``campaign``): ``fixture_pose`` (offset of one clamping
position), ``rod_deflection`` (compensation off by a factor: residuals follow R_T^W (C_g g + C_F F)),
``periodic_joint_error`` (once or twice per revolution of joint K along the joint's motion), ``thermal_drift``
(link growth with time_s / temp_C), ``outliers`` (isolated gross alignment errors: per-point candidates that do
not use up the model terms), and rodlab's additions ``device_axes``, ``lost_motion`` and ``joint_stiffening``; one
angle error per joint. Each effect also says how its finding enters the
re-identification (:class:`~rodlab.calibrate.effects.Refit`).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np
from rodlab.calibrate import FitOptions, Rod, campaign_observations, identify
from rodlab.calibrate.effects import (CAMPAIGN_EFFECTS, CampaignContext, campaign_effect, campaign_hypotheses)
from rodlab.calibrate.jacobian import position_jacobian
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.identify import STRICT_HINT
from rodlab.calibrate.kinematics import ball_positions
from rodlab.calibrate.mixups import campaign_mixup
from rodlab.calibrate.observations import noise_covariance
from rodlab.calibrate.validate import error_stats
from rodlab.core.enums import Subject, Trial, Verdict
from rodlab.core.hypothesis import Hypothesis, location_parts

from .criteria import DBIC_MIN, Evidence, bic_penalty, cv_improves, evidence, weakest_term
from .report import Diagnosis, Finding
from .robust import median_reduced_chi2, robust_fit
from .search import search
from .campaign_excess import device_noise_null, unexplained_finding
from .campaign_fits import CampaignFits
from .campaign_forms import completes, deferred, merge_completed, resolved_first, rival_forms, same_place
from .campaign_holdout import check_on_validation
from .campaign_refit import deflection_of, reidentify, validation_errors

__all__ = ["diagnose_campaign", "CampaignFits", "CampaignSelection", "campaign_context", "device_noise_null"]

log = logging.getLogger(__name__)

#: significant candidates tried in turn at each step when the best fails cross-validation
FALLBACKS = 4


def _birge_drop(e: np.ndarray, n: int, k: int, birge: float) -> float:
    """Factor (>= 1) by which the Birge ratio falls once accepted terms are fitted: ``e`` are the whitened
    residuals of the current model (k parameters), robust per-point reduced chi-square as at the start."""
    chi_red = median_reduced_chi2(e, n, k)
    new = max(birge * float(np.sqrt(chi_red)), 1.0)
    return max(birge / new, 1.0)


@dataclass
class _Candidate:
    """One hypothesis (or an outlier point) tried next: its :class:`~.criteria.Evidence`, whitened columns, and
    the fit with it (coefficients of all columns, residual sum of squares)."""

    ev: Evidence
    hyp: Hypothesis
    coef: np.ndarray
    rss: float


class CampaignSelection:
    """Forward selection of hypotheses on the whitened residuals of the identified campaign.

    The residuals r and the Jacobian J of the free parameters are whitened with the noise covariance (device
    noise + fixture-pose uncertainty per position; its symmetric square root, so each whitened reading stays its
    point) times the Birge ratio: a campaign has no repeats, so scatter the noise model leaves out shows only as
    chi-square above its degrees of freedom, and an effect must stand out of what the campaign's own residuals
    allow. The ratio starts from a robust (Tukey biweight) fit, so gross errors cannot inflate it and hide
    themselves, and falls (median per point) as accepted terms explain the residuals.
    """

    def __init__(self, ctx: CampaignContext, tau: np.ndarray, noise_mm: float, fixture_sigma, max_terms: int):
        res, obs, fr = ctx.result, ctx.obs, ctx.frames
        self.ctx, self.noise_mm, self.N = ctx, noise_mm, ctx.n_points
        self.max_terms, self.max_outliers = max_terms, max(2, self.N // 10)
        free_infos = [i for i in res.infos if i.name in res.free]
        J = position_jacobian(fr, tau, free_infos, res.params.base, obs.group).reshape(3 * self.N, -1)
        # the symmetric square root of the covariance: each whitened reading stays that reading (a Cholesky
        # factor would fold a position's first point into all its later rows, hiding a gross error there)
        self.cov = noise_covariance(obs, noise_mm, fixture_sigma)
        self.cov_device = noise_covariance(obs, noise_mm, (0.0, 0.0))
        w, V = np.linalg.eigh(self.cov)
        L = (V * np.sqrt(w)) @ V.T
        self.r_raw = res.residuals_mm.reshape(-1)
        self.n = self.r_raw.size
        r0, J0 = np.linalg.solve(L, self.r_raw), np.linalg.solve(L, J)
        # the scatter of the points without the gross errors a least-squares fit would smear over all
        chi_red0 = robust_fit(J0, r0).reduced_chi2
        self.birge = float(np.sqrt(max(chi_red0, 1.0)))
        log.debug("campaign diagnosis: robust reduced chi-square %.2f, Birge ratio %.2f", chi_red0, self.birge)
        self.L = L * self.birge
        self.r, self.J = r0 / self.birge, J0 / self.birge
        self.hyps = [replace(h, X=self.white(h.X)) for h in campaign_hypotheses(ctx)]
        self.cols: list = []
        self.col_hyps: list[Hypothesis] = []   # the hypothesis of each accepted column block
        self.chosen: list = []           # (effect, location) accepted, outliers included
        self.used_points: list[int] = []
        self.findings: list[Finding] = []
        self.ranked: list[_Candidate] = []   # the last ranking of the candidates (rival forms of a finding)
        # the baseline is the generalised-least-squares refit of the identified parameters (the identification
        # itself is unweighted): what that refit gains must not be credited to the first hypothesis
        self.rss = self.fit(self.cols)[1]
        self.cv = self.cv_error(self.cols)

    def white(self, A):
        return np.linalg.solve(self.L, A)

    def fit(self, cols):
        A = np.column_stack([self.J] + cols) if cols else self.J
        coef, *_ = np.linalg.lstsq(A, self.r, rcond=None)
        e = self.r - A @ coef
        return coef, float(e @ e), e

    def rms(self, cols) -> float:
        """rms per reading [mm] of the (unwhitened) residuals of the model with ``cols``."""
        e = self.L @ self.fit(cols)[2]
        return float(np.sqrt(np.mean(e ** 2)))

    def cv_error(self, cols, skip=()):
        """Leave-one-point-out prediction error (a position-specific term is still estimable); points in
        ``skip`` (dropped as outliers: their own columns absorb them) are not predicted."""
        total = 0.0
        A = np.column_stack([self.J] + cols) if cols else self.J
        for i in range(self.N):
            if i in skip:
                continue
            test = np.zeros(3 * self.N, dtype=bool)
            test[3 * i:3 * i + 3] = True
            coef, *_ = np.linalg.lstsq(A[~test], self.r[~test], rcond=None)
            total += float(((self.r[test] - A[test] @ coef) ** 2).sum())
        return total

    def rescale(self) -> None:
        """Re-estimate the inflated scatter without what the accepted terms explain: a gross error (outliers, a
        wrong fixture pose) spreads through the identification into every residual and must not hide a
        second one behind a large Birge ratio."""
        f = _birge_drop(self.fit(self.cols)[2], self.n, self.J.shape[1] + sum(c.shape[1] for c in self.cols),
                        self.birge)
        if f > 1.0:
            self.birge /= f
            self.L = self.L / f
            self.r, self.J = self.r * f, self.J * f
            self.hyps = [replace(h, X=h.X * f) for h in self.hyps]
            self.cols = [c * f for c in self.cols]
            self.rss, self.cv = self.rss * f * f, self.cv * f * f
            log.debug("campaign diagnosis: Birge ratio re-estimated to %.2f", self.birge)

    def _candidate(self, h: Hypothesis, penalty: float) -> _Candidate:
        coef, rss2, _ = self.fit(self.cols + [h.X])
        return _Candidate(evidence(self.rss - rss2, h.X.shape[1], penalty), h, coef, rss2)

    def candidates(self, max_outliers: int) -> list[_Candidate]:
        """Every hypothesis not yet accepted, and the point with the largest robust residual as an outlier (a
        least-squares fit smears a gross error onto its neighbours and can point at an innocent point)."""
        cand = [self._candidate(h, bic_penalty(h.X.shape[1] + h.hidden, self.n)) for h in self.hyps
                if not any(same_place(c, h) for c in self.chosen) or completes(h, self.col_hyps)]
        A = np.column_stack([self.J] + self.cols) if self.cols else self.J
        norms = np.linalg.norm(robust_fit(A, self.r).residuals, axis=1)
        order = [int(i) for i in np.argsort(-norms) if int(i) not in self.used_points]
        if order and len(self.used_points) < max_outliers:
            for model in CAMPAIGN_EFFECTS.values():
                h = model.point_hypothesis(order[0], self.ctx) if model.per_point else None
                if h is not None:
                    # a single point can absorb 3 dof: demand a large, isolated error (Bonferroni over N points)
                    cand.append(self._candidate(replace(h, X=self.white(h.X)),
                                                3 * np.log(self.n) + 2 * np.log(self.N)))
        self.ranked = deferred(resolved_first(sorted(cand, key=lambda c: c.ev.dbic)))
        return self.ranked

    def try_accept(self, best: _Candidate) -> bool:
        """Accept ``best`` if it passes delta BIC, the likelihood-ratio test, cross-validation and the detection
        limit; record its finding. False: the next candidate may try (:meth:`trial`)."""
        h, per_point = best.hyp, campaign_effect(best.hyp.effect).per_point
        if not best.ev.significant:
            log.debug("campaign diagnosis: %s %s not significant (dBIC %.1f, p %.2g)", h.effect, h.location,
                      best.ev.dbic, best.ev.p)
            return False
        if per_point:
            cv2 = self.cv * (best.rss / max(self.rss, 1e-300))
        else:                             # both models predicted on the same points (outliers left out)
            self.cv = self.cv_error(self.cols, self.used_points) if self.used_points else self.cv
            cv2 = self.cv_error(self.cols + [h.X], self.used_points)
        if not cv_improves(self.cv, cv2):
            log.debug("campaign diagnosis: %s %s does not predict left-out points better (%.4g -> %.4g)",
                      h.effect, h.location, self.cv, cv2)
            return False
        A = np.column_stack([self.J] + self.cols + [h.X])
        k0 = self.J.shape[1] + sum(c.shape[1] for c in self.cols)
        val = best.coef[k0:k0 + h.X.shape[1]]
        # detection limit: an effect that moves no point by 2 SDs of the scatter it leaves is not reported (the
        # scatter before it would count the effect itself: a backlash 0.02 deg raised its own bar and was never named)
        left = self.birge / _birge_drop(self.r - A @ best.coef[:A.shape[1]], self.n, A.shape[1], self.birge)
        if not per_point and float(np.max(np.abs(self.L @ (h.X @ val)))) < 2.0 * self.noise_mm * left:
            log.debug("campaign diagnosis: %s %s below the detection limit", h.effect, h.location)
            return False
        se = np.sqrt(np.clip(np.diag(np.linalg.pinv(A.T @ A))[k0:k0 + h.X.shape[1]], 0, None))
        self._record(best, cv2, *h.reported(val, se))
        return True

    def _record(self, best: _Candidate, cv2: float, params: dict, iv: dict) -> None:
        h = best.hyp
        merged = campaign_effect(h.effect).per_point and self._merge_point(h)
        if not merged:
            before = self.rms(self.cols) if self.cols else float(np.sqrt(np.mean(self.r_raw ** 2)))
            ev = dict(best.ev.to_dict(), cv_sse_before=float(self.cv), cv_sse_after=float(cv2))
            alts = rival_forms(best, self.ranked)
            if alts:
                ev["alternatives"] = alts
            self.findings.append(Finding(h.effect, h.location, h.explanation, params, iv, before,
                                         self.rms(self.cols + [h.X]), ev))
        self.chosen.append((h.effect, h.location))
        self.cols.append(h.X)
        self.col_hyps.append(h)
        self.rss, self.cv = best.rss, cv2

    def _merge_point(self, h: Hypothesis) -> bool:
        """A per-point finding: note the point; True if it joined an earlier finding of its effect (one finding
        lists the points)."""
        lab = location_parts(h.location)[1]
        self.used_points.append(int(self.ctx.labels.index(lab)))
        prev = [f for f in self.findings if f.effect == h.effect]
        if not prev:
            return False
        prev[0].location += "," + lab
        prev[0].rms_after_mm = self.rms(self.cols + [h.X])
        return True

    # --- the campaign's SearchSpace (.search): extend the current model by one hypothesis or one outlier point
    tries = FALLBACKS
    keep_growing = False

    def exhausted(self) -> bool:
        """``max_terms`` physical terms are in (outliers are points, not physics)."""
        return sum(not campaign_effect(e).per_point for e, _ in self.chosen) >= self.max_terms

    def grow(self) -> list[_Candidate]:
        """Re-estimate the scatter with what is accepted, then rank the next candidates."""
        if self.cols:
            self.rescale()
        cand = self.candidates(self.max_outliers)
        if cand:
            log.debug("campaign diagnosis: best %s %s dBIC %.1f; next %s", cand[0].hyp.effect, cand[0].hyp.location,
                      cand[0].ev.dbic, [(c.hyp.effect, c.hyp.location, round(c.ev.dbic, 1)) for c in cand[1:4]])
        return cand

    def trial(self, candidate: _Candidate) -> Trial:
        """The significant candidates in order: one that fails cross-validation or the detection limit (a
        flexible term absorbing part of a gross error) gives way to the next."""
        if candidate.ev.dbic > -DBIC_MIN:
            return Trial.NEXT
        return Trial.ACCEPT if self.try_accept(candidate) else Trial.NEXT

    def finish(self) -> None:
        """Drop-one test, as the rig's: a physical term accepted early that the final model no longer needs is
        removed, the weakest first, while one fails. A flexible term (the device's axes, say) can win the first
        step by absorbing part of a gross error that the outlier points and a fixture pose, accepted after it,
        explain in full; kept, it bends the re-identification and leaves a residual pattern elsewhere."""
        while True:
            physical = [k for k, (effect, _) in enumerate(self.chosen) if not campaign_effect(effect).per_point]
            k = weakest_term(physical, lambda k: self.fit(self.cols[:k] + self.cols[k + 1:])[1] - self.rss,
                             lambda k: self.cols[k].shape[1] + self.col_hyps[k].hidden, self.n)
            if k is None:
                break
            self._drop(k)
        self._joint_parameters()
        self.findings = merge_completed(self.findings)

    def _joint_parameters(self) -> None:
        """Each finding's parameters and intervals from the final model's joint fit: a term accepted early was
        estimated without the later ones, and two correlated terms (a periodic error and a non-linear spring of the
        same joint) would otherwise both carry the part they share into the re-identification."""
        if not self.cols:
            return
        coef = self.fit(self.cols)[0]
        A = np.column_stack([self.J] + self.cols)
        var = np.clip(np.diag(np.linalg.pinv(A.T @ A)), 0, None)
        k = self.J.shape[1]
        for h, c in zip(self.col_hyps, self.cols):
            w = c.shape[1]
            if not campaign_effect(h.effect).per_point:
                params, iv = h.reported(coef[k:k + w], np.sqrt(var[k:k + w]))
                for f in self.findings:
                    if f.effect == h.effect and f.location == h.location and set(h.names) <= set(f.parameters):
                        f.parameters, f.intervals = params, iv
            k += w

    def _drop(self, k: int) -> None:
        """Remove the ``k``-th accepted term and its finding (drop-one test)."""
        effect, location = self.chosen.pop(k)
        self.cols.pop(k)
        names = set(self.col_hyps.pop(k).names)          # a harmonic beside another at its joint: that one only
        self.findings = [f for f in self.findings
                         if not (f.effect == effect and f.location == location and names <= set(f.parameters))]
        self.rss = self.fit(self.cols)[1]
        self.cv = self.cv_error(self.cols, self.used_points)
        log.debug("campaign diagnosis: %s %s dropped: the final model does not need it", effect, location)

    def run(self) -> None:
        """Select until ``max_terms`` physical terms (up to a tenth of the points as outliers besides) or until
        no candidate passes. Every step accepts one term or ends the search, and outlier candidates are offered
        only while fewer than ``max_outliers`` points are dropped, so the step bound never cuts it short."""
        search(self, self.max_terms + self.max_outliers + 1)


#: the re-identification with the found physics is flagged when its rms exceeds the plain one by this factor
REFIT_WORSE = 1.1


def campaign_context(robot, res, obs, camp, rod) -> tuple[CampaignContext, np.ndarray]:
    """The identified campaign as hypotheses see it, and the joint torques [N m] at its points."""
    fr, tau = ball_positions(robot, res.params, obs.q_rad, obs.rod, force_W_N=obs.force_W_N)
    return CampaignContext(robot, res, obs, np.asarray(camp.position), camp.labels(), camp.time_s, camp.temp_C, rod,
                           fr, tau), tau


def _refuse_unexplained_mixup(robot, res, camp, fix, rod, obs, options) -> None:
    """Where no modelled physics explains material residuals, the files' mix-ups are screened as ``rodlab calibrate``
    screens them (:func:`~rodlab.calibrate.mixups.campaign_mixup`): a reading column negated leaves 72 um rms, not
    gross, and had been diagnosed as a device 29 times noisier than stated. Raises the mix-up's reason."""
    mixup = campaign_mixup(robot, res, camp, fix, rod, obs, Rod.of(rod), [deflection_of(rod)], options, suspect=True)
    if mixup is not None:
        where = dict(path=fix.path, key="positions") if mixup.fixture_radians else dict(path=camp.path, key="campaign")
        raise CalibrationError(f"{mixup.reason()}; no modelled physics explains these files as given (if they are "
                               "right as they are, give --columns-checked)", **where)


def diagnose_campaign(robot, camp, fix, rod, noise_mm: float = 0.003, validate_points=None, max_terms: int = 3,
                      fixture_sigma=(0.01, 0.002), harmonics=(), columns_checked: bool = False):
    """Diagnose a campaign; returns the report and the :class:`CampaignFits` behind it. ``harmonics``: joints
    whose periodic errors the calibration already identifies (``--joint-harmonics``), not hypotheses then.
    A mix-up of the files (a reversed joint, swapped positions, a fixture in radians) is refused, or with
    ``columns_checked`` (``--columns-checked``: the user states the files are right) logged and diagnosed."""
    obs = campaign_observations(camp, fix, rod)
    # the identification runs the residual test of `rodlab calibrate` (its trust verdict), with this noise model
    options = FitOptions(expected_noise_mm=noise_mm, fixture_sigma=fixture_sigma, harmonics=tuple(harmonics))
    try:
        res = identify(robot, obs, Rod.of(rod), [deflection_of(rod)], options)
    except CalibrationError as e:      # the diagnosis identifies every parameter: no --strict to drop here
        if STRICT_HINT not in e.detail:
            raise
        raise CalibrationError(e.detail.replace(STRICT_HINT, "") + " (the diagnosis identifies every parameter)",
                               path=e.path or camp.path, key=e.key) from e
    mixup = campaign_mixup(robot, res, camp, fix, rod, obs, Rod.of(rod), [deflection_of(rod)], options, material=False)
    if mixup is not None and columns_checked:
        log.warning("%s: %s (--columns-checked: diagnosed as they are)", camp.path, mixup.reason())
    elif mixup is not None:                # the files do not describe one robot: no physics to diagnose
        where = dict(path=fix.path, key="positions") if mixup.fixture_radians else dict(path=camp.path, key="campaign")
        raise CalibrationError(f"{mixup.reason()}; the diagnosis of these files would name the mix-up's traces as "
                               "physics (if the files are right as they are, give --columns-checked)", **where)
    ctx, tau = campaign_context(robot, res, obs, camp, rod)
    sel = CampaignSelection(ctx, tau, noise_mm, fixture_sigma, max_terms)
    sel.run()
    findings = sel.findings
    res2, refit = (None, None)
    if findings:
        res2, refit = reidentify(robot, camp, fix, rod, ctx, findings, noise_mm, fixture_sigma)
    final_test = res2.residual_check if res2 is not None else res.residual_check
    verdict = Verdict.CONSISTENT if not findings else Verdict.EXPLAINED
    if not findings and final_test.material and not columns_checked:
        _refuse_unexplained_mixup(robot, res, camp, fix, rod, obs, options)
    if final_test.missing:                 # calibrate's residual test: one story between the two
        findings.append(unexplained_finding(sel, camp, final_test))
        verdict = Verdict.UNEXPLAINED
    extra = {"residual_test": {"before": res.residual_check.to_dict(), "after": final_test.to_dict()}}
    keep = refit.keep if refit is not None else np.ones(ctx.n_points, dtype=bool)
    fits = CampaignFits(res, res2, keep, camp.labels(), np.asarray(camp.position),
                        refit.joint_corrections_rad if refit is not None else {},
                        q_deg=np.asarray(camp.q_deg, float),
                        time_s=None if camp.time_s is None else np.asarray(camp.time_s, float),
                        torque_corrections=refit.torque_corrections if refit is not None else {})
    if validate_points is not None:
        fits.validation_errors_mm = validation_errors(robot, fits, validate_points)
        extra["validation"] = {k: error_stats(e).to_dict() for k, e in fits.validation_errors_mm.items()}
        check_on_validation(robot, camp, fix, rod, ctx, findings, noise_mm, fixture_sigma, validate_points,
                            fits.validation_errors_mm["after"])
    rms_after = res2.rms_mm if res2 is not None else res.rms_mm
    if rms_after > REFIT_WORSE * res.rms_mm:
        extra["refit_warning"] = (f"the identification with the found physics fits worse than without it (rms "
                                  f"{res.rms_mm * 1e3:.2f} -> {rms_after * 1e3:.2f} um): the findings' parameters "
                                  "do not carry over to it; do not apply them, and report this campaign")
    return Diagnosis(Subject.CAMPAIGN, verdict, noise_mm, res.rms_mm, rms_after, findings, extra), fits
