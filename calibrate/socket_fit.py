"""Identification from ball-in-socket and ball-bar readings, jointly across placements (MUKCa-style data).

Unknowns: the robot's parameters (the catalogue of :mod:`calibrate.params`) and one centre per placement and
socket (ball bar: per pivot). Whitened residuals, each divided by its stated standard uncertainty:

- a seat reading: the ball centre ``p(q)`` minus its socket's centre (3 per reading);
- a ball-bar reading: ``|p(q) - c| - length`` (1 per reading);
- a known socket distance at every placement that has both sockets: ``|c_a - c_b| - D``.

The base pose is the frame the centres are fitted in (any rigid motion of the base moves every centre with
it): it is held at the description's, and the centres are reported in {0}. Without a known distance (or a
ball bar's length) the overall scale is not observable either, and a fit would shrink the robot (the seat
residuals scale with it): the longest row's length is then held, by rule, with that reason. Joint compliances
of a chain without link masses are held (no torque), and so is any parameter a change of its plausible size
would move the readings by less than one standard uncertainty in all (a wrist joint's compliance). The tool's
azimuth about the last axis is free (``tool_y``), ``dtheta_n`` held, as for instrument points. With
``robust``, the verdict and the standard errors still count every reading in full (the loss changes the
estimate, not the test).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from .covariance import correlation, parameter_covariance
from .errors import CalibrationError
from .estimate import Selection, check_names, parameter_value, pinned_vector, select_free, solve
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .params import INTERNAL_SCALE, PRIOR_SCALE, apply, catalogue, structural_fixed
from .residual_test import P_MISSING, ResidualTest
from .result import CalibrationResult
from .socket_check import socket_centres
from .sockets import SocketReadings
from .trust import trust_cautions, trust_warnings

__all__ = ["SocketFit", "identify_sockets", "socket_start", "BASE_GAUGE", "SCALE_HELD"]

log = logging.getLogger(__name__)

BASE_GAUGE = "held: the sockets' places are unknown, so the base pose is only the frame they are fitted in"
SCALE_HELD = ("held: it sets the overall scale, which no known socket distance (# distance_mm) or ball-bar length "
              "fixes in these readings")


@dataclass(frozen=True)
class SocketFit:
    """An identification from socket readings.

    result : the robot's parameters, residuals (N, 3) [mm] (seat: ball minus centre; ball bar: the length error
    along the bar), trust verdict, as for any calibration; centres_mm : {(placement, socket): shape=(3,)
    centre in {0} [mm]}; centre_sigma_mm : same keys, shape=(3,) 1-sigma [mm]; distance_residuals_mm :
    shape=(K,) fitted centre distance minus the stated one [mm], one per placement and known pair
    """

    result: CalibrationResult
    centres_mm: dict
    centre_sigma_mm: dict
    distance_residuals_mm: np.ndarray


@dataclass(frozen=True)
class _Problem:
    """What the residuals need: the readings, the group (centre) of each, the distance rows (ga, gb, D)."""

    readings: SocketReadings
    group: np.ndarray
    pairs: np.ndarray          # (K, 2) int: centre indices
    pair_mm: np.ndarray        # (K,) stated distances [mm]

    @property
    def G(self) -> int:
        return int(self.group.max()) + 1

    @classmethod
    def of(cls, r: SocketReadings) -> "_Problem":
        return cls(r, r.group_index(), *r.distance_pairs())


def socket_start(robot, readings: SocketReadings) -> ModelParams:
    """The nominal model the fit starts from: the file's tool, else the description's tip point; base 0."""
    tool = readings.tool_mm if readings.tool_mm is not None else np.asarray(robot.n_T_tip, float)[:3, 3]
    return ModelParams.nominal(robot, tool)


def _blocks(robot, p: ModelParams, q_rad, C: np.ndarray, prob: _Problem, infos_free: list, with_jac: bool):
    """Whitened residuals and their Jacobian columns (robot parameters, then centres)."""
    r = prob.readings
    fr, tau = ball_positions(robot, p, q_rad)
    d = fr.pW - C[prob.group]
    N, G, P = d.shape[0], prob.G, len(infos_free)
    Jr = position_jacobian(fr, tau, infos_free, p.base) if with_jac and P else np.zeros((N, 3, P))
    rows = np.arange(N)
    if r.length_mm is None:
        res = (d / r.seat_sigma_mm).ravel()
        Jc = np.zeros((N, 3, 3 * G))
        for k in range(3):
            Jc[rows, k, 3 * prob.group + k] = -1.0
        Jm = np.concatenate([Jr, Jc], axis=2).reshape(3 * N, P + 3 * G) / r.seat_sigma_mm
    else:
        rho = np.linalg.norm(d, axis=1)
        u = d / rho[:, None]
        res = (rho - r.length_mm) / r.length_sigma_mm
        Jc = np.zeros((N, 3 * G))
        for k in range(3):
            Jc[rows, 3 * prob.group + k] = -u[:, k]
        Jm = np.concatenate([np.einsum("ni,nip->np", u, Jr), Jc], axis=1) / r.length_sigma_mm
    return res, Jm, fr


def _distance_blocks(C: np.ndarray, prob: _Problem, P: int):
    """Whitened residuals of the known distances and their Jacobian (zero in the robot columns)."""
    K = prob.pairs.shape[0]
    e = C[prob.pairs[:, 0]] - C[prob.pairs[:, 1]]
    rho = np.linalg.norm(e, axis=1)
    s = prob.readings.distance_sigma_mm
    J = np.zeros((K, P + 3 * prob.G))
    u = e / np.maximum(rho, 1e-12)[:, None]
    for k in range(3):
        J[np.arange(K), P + 3 * prob.pairs[:, 0] + k] = u[:, k] / s
        J[np.arange(K), P + 3 * prob.pairs[:, 1] + k] = -u[:, k] / s
    return (rho - prob.pair_mm) / s, J


@dataclass
class _State:
    """Where the socket fit stands: the internal parameter vector ``x``, the free parameters, which of them carry a
    prior (bool, one per catalogue entry), the socket centres (G, 3) [mm] and the last solver result."""

    x: np.ndarray
    free: list
    prior: np.ndarray
    C: np.ndarray
    sol: object = None


def _functions(robot, start, infos, prob: _Problem, st: _State, x0: np.ndarray):
    """Pure residual and Jacobian of ``z = [free robot parameters (internal units), centres (mm)]`` around the
    state ``st``; the priors pull towards ``x0`` (the free parameters' start values)."""
    x, free, prior = st.x, st.free, st.prior
    P = len(free)
    infos_free = [infos[k] for k in free]
    scale = np.array([PRIOR_SCALE[infos[k].unit] * INTERNAL_SCALE[infos[k].unit] for k in free])
    sel = np.nonzero(prior[free])[0]

    def split(z):
        xx = x.copy()
        xx[free] = z[:P]
        return apply(start, infos, xx), z[P:].reshape(-1, 3)

    def fun(z):
        p, C = split(z)
        res, _, _ = _blocks(robot, p, prob.readings.q_rad, C, prob, infos_free, False)
        return np.concatenate([res, _distance_blocks(C, prob, P)[0], (z[sel] - x0[sel]) / scale[sel]])

    def jac(z):
        p, C = split(z)
        _, Jm, _ = _blocks(robot, p, prob.readings.q_rad, C, prob, infos_free, True)
        Jp = np.zeros((sel.size, z.size))
        Jp[np.arange(sel.size), sel] = 1.0 / scale[sel]
        return np.vstack([Jm, _distance_blocks(C, prob, P)[1], Jp])

    return fun, jac


def _rule_held(robot, prob: _Problem, pinned: dict) -> dict:
    """Parameters these readings cannot see by construction, with the reason: the base (gauge); the joint
    compliances of a chain without link masses (no torque); without a known distance or a ball bar's lengths,
    one length, the longest row's, which sets the overall scale."""
    held = {f"base_{k}": BASE_GAUGE for k in "xyzabc"}
    if not np.any(robot.mass_kg):
        held |= {f"c_{i + 1}": "the robot description has no link masses (<inertial>): no joint torque to see a "
                               "compliance by" for i in range(robot.n)}
    if not prob.pairs.size and not prob.readings.ball_bar:
        structural = structural_fixed(robot, np.zeros(3))
        lengths = [(abs(float(v[i])), f"{k}_{i + 1}") for k, v in (("d", robot.d_mm), ("a", robot.a_mm))
                   for i in range(robot.n) if f"{k}_{i + 1}" not in structural]
        held[max(lengths)[1]] = SCALE_HELD
    return {nm: why for nm, why in held.items() if nm not in pinned}


def _free_parameters(robot, start, prob: _Problem, C0, sel: Selection):
    """The parameters to fit: structural rules, the rules of socket data (:func:`_rule_held`), then the rank
    analysis of the robot's columns projected off the centres' (what a centre absorbs is not information about
    the robot), around the centres ``C0``."""
    infos, pinned, freed, fix_unidentifiable = sel.infos, sel.pinned, set(sel.freed), sel.fix_unidentifiable
    P = len(infos)
    fun, jac = _functions(robot, start, infos, prob, _State(np.zeros(P), list(range(P)), np.zeros(P, bool), C0),
                          np.zeros(P))
    J = jac(np.concatenate([np.zeros(len(infos)), C0.ravel()]))
    Jp = _off_centres(J, len(infos))
    rules = _rule_held(robot, prob, pinned)
    rules |= _negligible(infos, Jp, set(rules) | set(pinned) | freed)
    free, reasons = select_free(robot, Selection(infos, start.tool, (), {nm: 0.0 for nm in rules} | dict(pinned),
                                                freed | {"tool_y"}), Jp)
    reasons |= rules
    structural = set(structural_fixed(robot, start.tool)) | {f"dtheta_{robot.n}"} | set(rules)
    deficient = {nm: why for nm, why in reasons.items()
                 if nm not in structural and why.startswith(("combined", "has no"))}
    if deficient and not fix_unidentifiable:
        lines = "; ".join(f"{nm} {why}" for nm, why in list(deficient.items())[:8])
        raise CalibrationError(f"these socket readings cannot identify {len(deficient)} parameter(s): {lines}. "
                               f"{_remedy(deficient, prob)}", path=prob.readings.path, key="sockets")
    if deficient:
        log.warning("held at nominal (not identifiable from these socket readings): %s", ", ".join(deficient))
    if not free:
        raise CalibrationError("these socket readings identify no parameter of the robot: record the ball in each "
                               "socket in varied arm configurations", path=prob.readings.path, key="sockets")
    return free, reasons


def _off_centres(J: np.ndarray, P: int) -> np.ndarray:
    """The first ``P`` (robot) columns of ``J`` projected off the centres' columns after them: what a centre
    absorbs is not information about the robot."""
    Jr, Jc = J[:, :P], J[:, P:]
    return Jr - Jc @ np.linalg.lstsq(Jc, Jr, rcond=None)[0]


def _negligible(infos, Jp: np.ndarray, skip: set) -> dict:
    """Parameters that a change of their plausible size (``PRIOR_SCALE``) moves the readings by less than one
    standard uncertainty in all (whitened columns ``Jp``): nothing to fit, held at nominal with that reason
    (a joint compliance whose joint carries almost no torque, e.g. the last joint under a light gripper)."""
    scale = np.array([PRIOR_SCALE[i.unit] * INTERNAL_SCALE[i.unit] for i in infos])
    effect = np.linalg.norm(Jp, axis=0) * scale
    return {i.name: f"too little effect on these readings: a change of {PRIOR_SCALE[i.unit]:g} {i.unit} moves "
                    f"them by {effect[k]:.2g} standard uncertainties in all" for k, i in enumerate(infos)
            if 0.0 < effect[k] < 1.0 and i.name not in skip}


def _remedy(deficient: dict, prob: _Problem) -> str:
    """What to do about parameters the readings cannot identify, in the terms of the data at hand."""
    out = []
    if any(nm.startswith("c_") for nm in deficient):
        out.append("a joint compliance c_i is seen only through the torque on its joint (the links' and the "
                   "ball's weight): vary the arm's configurations more, or hold it with --pin c_i=0")
    out.append("record more varied arm configurations per socket and placements spread over the workspace, hold "
               "them with --pin NAME=VALUE (without --strict rodlab holds them at nominal itself)")
    text = "; ".join(out)
    return text[0].upper() + text[1:]


def _covariance(J: np.ndarray, reduced: float) -> np.ndarray:
    """Parameter covariance of a whitened problem, scaled by the residuals' reduced chi-square (at least 1);
    see :func:`calibrate.covariance.parameter_covariance` (a direction the readings do not see: infinite)."""
    return parameter_covariance(J) * max(reduced, 1.0)


def identify_sockets(robot, readings: SocketReadings, *, pinned: dict | None = None, freed=(),
                     fix_unidentifiable: bool = False, robust: bool = False, max_passes: int = 3) -> SocketFit:
    """Fit the robot and the socket centres to ``readings`` (see the module docstring); ``robust``: a soft-L1
    loss that lets readings beyond about 3 sigma lose weight (a ball not fully seated)."""
    pinned, freed = dict(pinned or {}), set(freed)
    infos = catalogue(robot.n)
    check_names([i.name for i in infos], pinned, freed)
    prob = _Problem.of(readings)
    start = socket_start(robot, readings)
    x = pinned_vector(infos, start, pinned)
    fr, _ = ball_positions(robot, apply(start, infos, x), readings.q_rad)
    C = socket_centres(fr.pW, readings)
    free, reasons = _free_parameters(robot, start, prob, C, Selection(infos, start.tool, (), pinned, freed,
                                                                      fix_unidentifiable))
    _check_size(readings, prob, free)
    prior = np.zeros(len(infos), bool)
    x0 = x.copy()
    st = _State(x, free, prior, C)
    for _ in range(max_passes):
        fun, jac = _functions(robot, start, infos, prob, st, x0[free])
        unbounded = (np.full(len(free) + C.size, -np.inf), np.full(len(free) + C.size, np.inf))
        sol = solve(fun, jac, np.concatenate([x[free], C.ravel()]), unbounded, robust, 3.0, 200 * (len(free) + C.size))
        x[free], C = sol.x[:len(free)], sol.x[len(free):].reshape(-1, 3)
        st.C, st.sol = C, sol
        reduced = float(sol.fun @ sol.fun) / max(sol.fun.size - sol.x.size, 1)
        sig = np.sqrt(np.diag(_covariance(sol.jac, reduced)))[:len(free)]
        weak = [k for k, s in zip(free, sig) if s / INTERNAL_SCALE[infos[k].unit] > PRIOR_SCALE[infos[k].unit]
                and not prior[k]]
        if not weak:
            break
        prior[weak] = True
        log.info("socket fit: %d weakly identified parameter(s) get a prior: %s", len(weak),
                 ", ".join(infos[k].name for k in weak))
    return _fit_result(robot, start, infos, reasons, prob, st)


def _check_size(readings: SocketReadings, prob: _Problem, free: list) -> None:
    m = (1 if readings.ball_bar else 3) * readings.n + prob.pairs.shape[0]
    unknowns = len(free) + 3 * prob.G
    if m <= unknowns:
        raise CalibrationError(f"{m} residuals for {len(free)} robot parameters and {prob.G} socket centres: too "
                               f"few readings; record more arm configurations per socket", path=readings.path,
                               key="sockets")


def _fit_result(robot, start, infos, reasons: dict, prob: _Problem, st: _State) -> SocketFit:
    """The calibration result (values, sigmas, status, residuals, trust) and the centres."""
    x, free, prior, sol, C = st.x, st.free, st.prior, st.sol, st.C
    r = prob.readings
    p = apply(start, infos, x)
    res_w = sol.fun
    dof = max(res_w.size - sol.x.size, 1)
    chi2 = float(res_w @ res_w)
    cov = _covariance(sol.jac, chi2 / dof)
    sig = np.sqrt(np.diag(cov))
    P = len(free)
    values = {i.name: parameter_value(p, i, x[k]) for k, i in enumerate(infos)}
    sigma = {i.name: 0.0 for i in infos} | {infos[k].name: float(s / INTERNAL_SCALE[infos[k].unit])
                                            for k, s in zip(free, sig[:P])}
    status = {i.name: "fixed" for i in infos} | {infos[k].name: "regularised" if prior[k] else "identified"
                                                 for k in free}
    resid_mm, seat_rms = _residuals_mm(robot, p, C, prob)
    corr = correlation(cov[:P, :P])
    Jr = _off_centres(sol.jac, P)
    Jn = Jr / np.maximum(np.linalg.norm(Jr, axis=0), 1e-300)
    out = CalibrationResult(p, infos, values, sigma, status,
                            [f"{nm} ({why})" for nm, why in reasons.items() if status.get(nm) == "fixed"],
                            resid_mm, seat_rms, _stated_noise(r) * np.sqrt(chi2 / dof), corr,
                            [infos[k].name for k in free], np.zeros_like(resid_mm), bool(sol.success),
                            str(sol.message), int(sol.nfev), 1, float(np.linalg.cond(Jn)) if P else float("nan"))
    out.residual_check = _residual_test(chi2, dof, r)
    out.warnings = trust_warnings(robot, out)     # residuals above the seat play: a caution (incomplete model)
    out.cautions = trust_cautions(out, robot)
    keys = r.groups()
    cs = sig[P:].reshape(-1, 3)
    return SocketFit(out, {g: C[k] for k, g in enumerate(keys)}, {g: cs[k] for k, g in enumerate(keys)},
                     _distance_blocks(C, prob, P)[0] * r.distance_sigma_mm)


def _residuals_mm(robot, p: ModelParams, C: np.ndarray, prob: _Problem) -> tuple[np.ndarray, float]:
    """Residuals in mm, shape=(N, 3) (measured minus model, the calibration result's sign: centre minus ball
    for a seat; for a ball bar the length error along the bar), and their rms per scalar reading."""
    fr, _ = ball_positions(robot, p, prob.readings.q_rad)
    d = fr.pW - C[prob.group]
    if prob.readings.length_mm is None:
        return -d, float(np.sqrt(np.mean(d ** 2)))
    rho = np.linalg.norm(d, axis=1)
    e = prob.readings.length_mm - rho
    return e[:, None] * d / rho[:, None], float(np.sqrt(np.mean(e ** 2)))


def _stated_noise(r: SocketReadings) -> float:
    """The stated uncertainty of one scalar reading [mm]: the seat's, or the ball bar's length."""
    return r.length_sigma_mm if r.ball_bar else r.seat_sigma_mm


def _residual_test(chi2: float, dof: int, r: SocketReadings) -> ResidualTest:
    from scipy.special import chdtrc  # heavy (scipy.special, ~0.15 s)
    p = float(chdtrc(dof, chi2))
    return ResidualTest(chi2, dof, chi2 / dof, p, _stated_noise(r), (), p < P_MISSING, clamping=False,
                        source="ball-bar length" if r.ball_bar else "seat")
