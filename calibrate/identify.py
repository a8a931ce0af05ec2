"""Levenberg-Marquardt identification (paper Eqs. 7-9) with rod-deflection compensation (Eqs. 10-19).

1. Measured points: ``x^W = T(chi_3j) x^D`` (Eq. 2); initial base by rigid registration of the nominal
   ball positions to them.
2. Identifiability: the structural rules (:mod:`calibrate.params`), then a rank analysis of the
   column-normalised Jacobian in preference order: a parameter whose column lies (numerically) in the span
   of those kept is fixed and reported with the combination it belongs to.
3. LM (``scipy.optimize.least_squares``, analytic Jacobian) on the free parameters; weakly identified
   parameters (standard error above their physical scale) get a Gaussian prior at their initial value and
   are reported ``regularised``.
4. Compensation: the ball offsets of every point by each of the ``compensations``
   (:mod:`calibrate.compensations`: the rod's deflection ``R_T^W (C_g g^T + C_F F^T)`` from its compliance, its
   thermal growth) are computed from the current model and removed from the measurement (Eq. 11); steps 3-4
   repeat until the offsets stop changing (the paper's rough calibration is the first pass).
5. Standard errors: sandwich estimate with the device noise (from the residuals) and the fixture-pose
   uncertainty, correlated within each clamping position.
"""
from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .compensations import Compensation, total_offsets
from .covariance import parameter_covariance
from .errors import CalibrationError
from .estimate import FitOptions, Selection, check_names, parameter_value, physical_bounds, pinned_vector, select_free, solve
from .jacobian import position_jacobian
from .kinematics import ModelParams, harmonic_reference
from .observations import Observations, campaign_observations, noise_covariance, register_base, register_base_and_tool
from .params import INTERNAL_SCALE, PRIOR_SCALE, apply, catalogue, structural_fixed
from .residual_test import residual_test
from .result import CalibrationResult
from .rod import Rod
from .trust import trust_cautions, trust_warnings

__all__ = ["Observations", "CalibrationResult", "identify", "campaign_observations", "register_base",
           "register_base_and_tool", "noise_covariance", "free_parameters", "harmonic_start"]

log = logging.getLogger(__name__)


def identify(robot, obs: Observations, rod: Rod, compensations: Sequence[Compensation] = (),
             options: FitOptions = FitOptions()) -> CalibrationResult:
    """Identify the robot (and base, tool, joint compliance) from ``obs``; see the module docstring.

    rod : the rod on the flange (:class:`~rodlab.calibrate.rod.Rod`): its tool vector starts the fit
    compensations : what is removed from the measurements, alternating with the fit (entries of
        :data:`~rodlab.calibrate.compensations.COMPENSATIONS`, e.g. ``[RodDeflection.of(rod), ThermalGrowth(...)]``);
        none: the rigid model
    options : pins, frees, loss, periodic joint errors, noise level (:class:`~rodlab.calibrate.estimate.FitOptions`)
    """
    if not isinstance(rod, Rod):
        raise TypeError(f"identify takes the rod as a Rod (Rod.of(compliance) or Rod.rigid(tool_mm)), got "
                        f"{type(rod).__name__}")
    _check_observations(obs)
    _check_harmonics(options.harmonics, robot.n)
    problem, reasons = _problem(robot, obs, rod, compensations, options)
    st = _compensate(robot, obs, problem, compensations, options)
    out = _result(robot, obs, problem, reasons, st, options.fixture_sigma)
    out.harmonic_range_deg = {j: (float(np.rad2deg(obs.q_rad[:, j - 1].min())), float(np.rad2deg(obs.q_rad[:, j - 1].max())))
                              for j in sorted(set(options.harmonics))}
    if options.expected_noise_mm:
        out.residual_check = residual_test(robot, out, obs, options.expected_noise_mm, options.fixture_sigma)
    out.warnings = trust_warnings(robot, out)
    out.cautions = trust_cautions(out, robot)
    return out


@dataclass
class _Problem:
    """What the compensation loop fits: the start model, the parameter catalogue, the internal vector ``x`` at
    the start (pins applied), the free parameters, those held in the first pass (``rough``) and the bounds."""

    start: ModelParams
    infos: list
    x: np.ndarray
    free: list
    rough: list
    lower: np.ndarray
    upper: np.ndarray


def _problem(robot, obs: Observations, rod: Rod, compensations, options: FitOptions) -> tuple[_Problem, dict]:
    """The catalogue, the start model, the free parameters (and why the others are held) and the bounds."""
    pinned, freed = dict(options.pinned), set(options.freed)
    positions = sorted(set(obs.group.tolist())) if obs.group is not None else []
    positions = [j for j in positions if obs.fixture_T is None or not np.allclose(obs.fixture_T[j], np.eye(4))]
    infos = catalogue(robot.n, positions, options.harmonics)
    check_names([i.name for i in infos], pinned, freed)
    start, tool_mm = _starting_model(robot, obs, rod.tool_mm, options.initial, options.find_tool)
    if options.harmonics or start.h.any():
        start = harmonic_start(start, obs.q_rad, options.harmonics)
    x = pinned_vector(infos, start, pinned)
    free, reasons = free_parameters(robot, obs, apply(start, infos, x), Selection.of(infos, tool_mm, positions, options))
    lower, upper = physical_bounds(infos, start)
    # rough calibration (paper Section 4.1): with a rod to compensate, the first pass holds the joint
    # compliances at their initial values, otherwise the wrist's c absorbs the uncompensated rod torsion
    rough = [k for k in free if infos[k].kind == "c"] if any(c.rough_pass for c in compensations) else []
    return _Problem(start, infos, np.clip(x, lower, upper), free, rough, lower, upper), reasons


def _check_observations(obs: Observations) -> None:
    N = obs.x_W_mm.shape[0]
    if N < 6:
        raise CalibrationError(f"{N} points cannot identify a robot; a MultiCal campaign has ~30 (5 positions x 6 "
                               f"orientations)", key="points")
    if not np.all(np.isfinite(obs.x_W_mm)) or not np.all(np.isfinite(obs.q_rad)):
        raise CalibrationError("the measurements contain NaN or inf", key="points")


def _check_harmonics(harmonics, n: int) -> None:
    bad = [j for j in harmonics if not (isinstance(j, (int, np.integer)) and 1 <= j <= n)]
    if bad:
        raise CalibrationError(f"joint harmonics: {bad} are not joints of this {n}-joint robot; give joint numbers "
                               f"1..{n}, e.g. 1,4")


def harmonic_start(start: ModelParams, q_rad: np.ndarray, harmonics) -> ModelParams:
    """The start model with the periodic terms of ``harmonics`` (joints, 1-based) centred on the readings ``q_rad``
    (N, n) [rad]; an ``initial`` model's terms keep their effect (the change of their means moves into the joint
    offsets), and an initial model with terms of joints not in ``harmonics`` is refused (they would be dropped)."""
    carried = {int(j) + 1 for j in np.nonzero(start.h.any(axis=1))[0]} - set(harmonics)
    if carried:
        raise CalibrationError(f"the initial model has periodic errors of joints {sorted(carried)} that would be "
                               f"dropped: list them in harmonics (--joint-harmonics) too")
    ref, new = start.h_ref.copy(), harmonic_reference(q_rad, harmonics)
    th = start.theta_offset.copy()
    for j in harmonics:
        th[j - 1] += start.h[j - 1] @ (new[j - 1] - ref[j - 1])
        ref[j - 1] = new[j - 1]
    return start.with_(h_ref=ref, theta_offset=th)


def _starting_model(robot, obs: Observations, tool_mm, initial, find_tool: bool):
    """The model the fit starts from (nominal with the base registered to the points, or ``initial``) and the
    tool [mm] (found from the data with ``find_tool``)."""
    start = initial or ModelParams.nominal(robot, tool_mm)
    if initial is None and find_tool:
        base0, tool0, rms0 = register_base_and_tool(robot, start, obs)
        log.info("base and tool from scratch: tool %s mm, registration rms %.3f mm", np.round(tool0, 2), rms0)
        return start.with_(base=base0, tool=tool0), tool0
    if initial is None:
        start = start.with_(base=register_base(robot, start, obs))
    return start, tool_mm


def free_parameters(robot, obs: Observations, model: ModelParams, sel: Selection) -> tuple[list, dict]:
    """The parameters to fit (indices into ``sel.infos``) and why the others are held, from the Jacobian of the
    model the fit starts from (``model``: pins applied) at the points ``obs``; refuses a data set that cannot
    identify what it must (unless ``sel.fix_unidentifiable``), naming the parameters and the remedy."""
    fr, tau = obs.balls(robot, model)
    J0 = position_jacobian(fr, tau, sel.infos, model.base, obs.group)
    free, reasons = select_free(robot, sel, J0)
    _refuse_deficient(obs, _deficient(robot, sel, reasons), sel.fix_unidentifiable)
    N = obs.x_W_mm.shape[0]
    if len(free) > 3 * N:
        raise CalibrationError(f"{len(free)} parameters from {3 * N} readings: too few points", key="points")
    return free, reasons


def _deficient(robot, sel: Selection, reasons: dict) -> dict:
    """The held parameters the data could not separate (beyond the structural rules), with the reason."""
    structural = structural_fixed(robot, sel.tool_mm, sel.positions)
    structural[f"dtheta_{robot.n}"] = structural.get(f"dtheta_{robot.n}", "") if "tool_y" in sel.freed else None
    structural = {k: v for k, v in structural.items() if v is not None}
    return {nm: why for nm, why in reasons.items() if nm not in structural and why.startswith(("combined", "has no"))}


#: the end of the refusal of a data set that cannot identify what it must: true for `calibrate --strict`, not for
#: a diagnosis, which identifies every parameter and has no --pin (its callers strip it)
STRICT_HINT = ", or hold them with --pin NAME=VALUE (without --strict rodlab holds them at nominal itself)"


def _refuse_deficient(obs: Observations, deficient: dict, fix_unidentifiable: bool) -> None:
    """A data set that cannot identify what it must is refused with the parameters and the remedy, or (with
    ``fix_unidentifiable``) those parameters are held at nominal and logged."""
    if deficient and fix_unidentifiable:
        log.info("held at nominal (not identifiable from these points): %s", ", ".join(deficient))
    elif deficient:
        lines = "; ".join(f"{nm} {why}" for nm, why in list(deficient.items())[:8])
        more = ("Add clamping positions or rod orientations (more varied joint angles)" if obs.group is not None
                else "Measure more poses spread over the workspace (every joint moved, varied configurations)")
        raise CalibrationError(
            f"{'this campaign' if obs.group is not None else 'these points'} cannot identify {len(deficient)} "
            f"parameter(s): {lines}. {more}{STRICT_HINT}",
            key="campaign" if obs.group is not None else "points")


@dataclass
class _Compensated:
    """The state the compensation loop ends in: internal parameters ``x``, which of them carry a prior, the
    compensation offsets in {W} [mm] (N, 3), the residual scatter [mm], the last solver result, the passes run
    and the parameters fitted in the last pass."""

    x: np.ndarray
    prior: np.ndarray
    offsets: np.ndarray
    noise_est: float
    res: object
    passes: int
    free: list


@dataclass
class _Pass:
    """One pass of the compensation loop: the internal vector ``x`` it starts from, the parameters it fits, the
    measurements minus the current offsets in {W} [mm] (N, 3), which parameters carry a prior, the scatter [mm]."""

    x: np.ndarray
    free: list
    target: np.ndarray
    prior: np.ndarray
    noise_est: float


def _residual_functions(robot, obs: Observations, problem: _Problem, step: _Pass):
    """The pure residual and its analytic Jacobian for one pass: ball positions minus the compensated
    measurements (fixture offsets applied), and the priors of the weak parameters (centred on their values at
    the start, ``problem.x``) scaled by the scatter."""
    infos, free, target, prior, noise_est = problem.infos, step.free, step.target, step.prior, step.noise_est
    x0 = problem.x[free]
    model_at = _memo_model(robot, problem.start, infos, step.x, free, obs)
    scale = np.array([PRIOR_SCALE[infos[k].unit] * INTERNAL_SCALE[infos[k].unit] for k in free])

    def fun(z):
        xx, p, frr, _ = model_at(z)
        r = (frr.pW - target - _fixture_shift(infos, xx, obs)).ravel()
        if prior[free].any():
            sel = prior[free]
            r = np.concatenate([r, noise_est * (z[sel] - x0[sel]) / scale[sel]])
        return r

    def jac(z):
        xx, p, frr, tt = model_at(z)
        Jm = position_jacobian(frr, tt, [infos[k] for k in free], p.base, obs.group).reshape(-1, len(free))
        if prior[free].any():
            sel = np.nonzero(prior[free])[0]
            Jp = np.zeros((sel.size, len(free)))
            Jp[np.arange(sel.size), sel] = noise_est / scale[sel]
            Jm = np.vstack([Jm, Jp])
        return Jm

    return fun, jac


def _compensate(robot, obs, problem: _Problem, compensations, options: FitOptions) -> _Compensated:
    """Identification and compensation alternate until the offsets stop changing (paper Eqs. 11-19): each pass
    fits the model to the measurements minus the offsets, then recomputes the offsets with the new model;
    parameters too weak for the data get a prior (once) and are refitted."""
    N = obs.x_W_mm.shape[0]
    start, infos, free_all, rough = problem.start, problem.infos, problem.free, problem.rough
    lower, upper, fixture_sigma = problem.lower, problem.upper, options.fixture_sigma
    x = problem.x.copy()                                # priors are centred on these initial values
    prior = np.zeros(len(infos), dtype=bool)
    released: set[int] = set()
    offsets = np.zeros_like(obs.x_W_mm)
    noise_est = 0.01
    res = None
    it = 0
    free = list(free_all)
    passes = options.max_compensation
    while it < passes:
        it += 1
        target = obs.x_W_mm - offsets
        free = [k for k in free_all if not (it == 1 and k in rough)]
        fun, jac = _residual_functions(robot, obs, problem, _Pass(x, free, target, prior, noise_est))
        res = solve(fun, jac, x[free], (lower[free], upper[free]), options.robust, 3 * noise_est,
                    options.max_nfev_per_parameter * len(free))
        x[free] = res.x
        p = apply(start, infos, x)
        new_off = total_offsets(compensations, robot, p, obs)
        change = float(np.abs(new_off - offsets).max())
        offsets = new_off
        r3 = obs.balls(robot, p)[0].pW - (obs.x_W_mm - offsets) - _fixture_shift(infos, x, obs)
        dof = max(3 * N - len(free), 1)
        noise_est = max(float(np.sqrt((r3 ** 2).sum() / dof)), 1e-6)
        # weak parameters -> prior (once), then refit
        sig = _sigmas(robot, obs, p, [infos[k] for k in free], noise_est, fixture_sigma)
        weak = [k for k, s in zip(free, sig) if s / INTERNAL_SCALE[infos[k].unit] > PRIOR_SCALE[infos[k].unit]]
        newly = [k for k in weak if not prior[k]]
        prior[newly] = True
        freed = _release_priors(prior, free, weak, released)
        log.info("compensation pass %d: offset change %.2e mm, rms %.4f mm, %d weak, %d released", it, change,
                 noise_est, len(newly), len(freed))
        if change < 1e-5 and not newly and not freed and len(free) == len(free_all):
            break
        if it == options.max_compensation and (newly or freed):
            passes = it + 1                   # the last pass changed the priors: one more solve under them
    return _Compensated(x, prior, offsets, noise_est, res, it, free)


def _release_priors(prior: np.ndarray, free: list, weak: list, released: set) -> list:
    """Take the prior off each parameter that carries one but is no longer weak (an early pass's scatter, before
    the compensation, had made it look weak: a tool length well determined had stayed ``regularised``); each
    parameter is released once at most, so a parameter at the edge cannot flip back and forth. Updates
    ``prior`` and ``released`` in place; returns the parameters released."""
    freed = [k for k in free if prior[k] and k not in weak and k not in released]
    prior[freed] = False
    released.update(freed)
    return freed


def _result(robot, obs, problem: _Problem, reasons, st: _Compensated, fixture_sigma) -> CalibrationResult:
    """The calibration result: values, standard deviations and status of every parameter, residuals."""
    x, free, start, infos = st.x, st.free, problem.start, problem.infos
    p = apply(start, infos, x)
    fr, tau = obs.balls(robot, p)
    resid = (obs.x_W_mm - st.offsets + _fixture_shift(infos, x, obs)) - fr.pW
    sig, corr, cond = _sigmas(robot, obs, p, [infos[k] for k in free], st.noise_est, fixture_sigma, full=True)
    values, sigma, status = {}, {}, {}
    for k, info in enumerate(infos):
        values[info.name] = parameter_value(p, info, x[k])
        status[info.name] = "fixed"
        sigma[info.name] = 0.0
    for s, k in zip(sig, free):
        sigma[infos[k].name] = float(s / INTERNAL_SCALE[infos[k].unit])
        status[infos[k].name] = "regularised" if st.prior[k] else "identified"
    unid = [f"{nm} ({why})" for nm, why in reasons.items() if status.get(nm) == "fixed"]
    rms = float(np.sqrt(np.mean(resid ** 2)))
    res = st.res
    ok = bool(res.success) if res is not None else False
    msg = res.message if res is not None else "not run"
    out = CalibrationResult(p, infos, values, sigma, status, unid, resid, rms, st.noise_est, corr,
                            [infos[k].name for k in free], st.offsets, ok, str(msg), int(res.nfev), st.passes, cond)
    return replace(out, unconstrained=_unconstrained(robot, obs, problem, st))


def _unconstrained(robot, obs, problem: _Problem, st: _Compensated) -> dict:
    """{name: value [rad/(N m)]} of each free joint compliance the fit holds at its lower bound (0): where one
    Gauss-Newton step from the fit, the bounds set aside, would put it (a trial: the sign convention of the measured
    points had put c_2 or c_3 at 0 without a word of how far below it the data pushed)."""
    free = st.free
    low = [i for i, k in enumerate(free) if problem.infos[k].kind == "c" and st.x[k] <= problem.lower[k] + 1e-9]
    if not low:
        return {}
    fun, jac = _residual_functions(robot, obs, problem, _Pass(st.x, free, obs.x_W_mm - st.offsets, st.prior,
                                                                st.noise_est))
    z = st.x[free]
    step = np.linalg.lstsq(jac(z), -fun(z), rcond=None)[0]
    out = {}
    for i in low:
        info = problem.infos[free[i]]
        out[info.name] = float(problem.start.c[info.index] + (z[i] + step[i]) / INTERNAL_SCALE[info.unit])
    return out


def _memo_model(robot, start: ModelParams, infos, x: np.ndarray, free: list, obs: Observations):
    """``z -> (internal vector, params, frames, torques)`` with the free parameters set to ``z``, remembering
    the last evaluation (the solver asks for the Jacobian at the point whose residual it just computed)."""
    last: dict = {}

    def model_at(z):
        z = np.asarray(z, float)
        if "z" in last and np.array_equal(last["z"], z):
            return last["out"]
        xx = x.copy()
        xx[free] = z
        p = apply(start, infos, xx)
        frr, tt = obs.balls(robot, p)
        last["z"], last["out"] = z.copy(), (xx, p, frr, tt)
        return last["out"]
    return model_at


def _fixture_shift(infos, x, obs) -> np.ndarray:
    """Corrections of the measured points by freed fixture offsets [mm], shape=(N, 3)."""
    shift = np.zeros_like(obs.x_W_mm)
    for info, v in zip(infos, x):
        if info.kind == "fixture" and v != 0 and obs.group is not None:
            shift[obs.group == info.index, "xyz".index(info.name[-1])] += v
    return shift


def _sigmas(robot, obs, p, free_infos: list, noise, fixture_sigma, full=False):
    """Sandwich standard errors (internal units) of the parameters ``free_infos`` with per-position correlated
    fixture-pose uncertainty; ``full``: also their correlation matrix and the Jacobian's condition number."""
    fr, tau = obs.balls(robot, p)
    J = position_jacobian(fr, tau, free_infos, p.base, obs.group).reshape(-1, len(free_infos))
    S = noise_covariance(obs, noise, fixture_sigma)
    C = parameter_covariance(J)                        # (J^T J)^-1, inf where the data see nothing
    JtJ_inv = np.nan_to_num(C, nan=0.0, posinf=0.0)
    cov = JtJ_inv @ J.T @ S @ J @ JtJ_inv
    cov[np.isinf(np.diag(C)), np.isinf(np.diag(C))] = np.inf
    sig = np.sqrt(np.clip(np.diag(cov), 0, None))
    if not full:
        return sig
    d = np.where(sig > 0, sig, 1.0)
    with np.errstate(invalid="ignore"):                # a parameter the data do not see: inf / inf, NaN (null)
        corr = cov / np.outer(d, d)
    Jn = J / np.maximum(np.linalg.norm(J, axis=0), 1e-300)
    sv = np.linalg.svd(Jn, compute_uv=False)
    return sig, corr, float(sv[0] / max(sv[-1], 1e-300))
