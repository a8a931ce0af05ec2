"""Predicted calibration accuracy of a rod on a robot without Monte Carlo: the identification linearised.

The identification (:func:`calibrate.identify.identify`) is a least-squares fit of the free parameters to the
measured ball centres; around the robot's nominal model it is linear: a data perturbation ``y`` (3N) moves the
identified parameters by ``A y``, ``A = (J^T J + L^T L)^-1 J^T`` with ``J`` the planned campaign's Jacobian
(3N x P) and ``L`` the priors of the weakly identified parameters. What perturbs the data of one campaign:

- the robot's own errors ``xi`` (kinematic, joint compliance; the truth's prior): ``J_all xi``; a perfect fit
  takes them out exactly, except along the regularised parameters (the priors' pull);
- the device noise and the recorded fixture poses' uncertainty ``eps ~ N(0, Sigma)``
  (:func:`calibrate.observations.noise_covariance`);
- what the compensation leaves of the rod's deflection: the offsets are linear in the compliance (Eq. 19,
  :func:`calibrate.compensations.deflection_basis` ``B``), so the error is the *bias*
  ``B vec(C_true - C_file)``, ``C_true = r S C_FEA S^T`` with ``r`` from the material's r_rod prior;
- what neither the model nor any compensation describes, drawn per draw and added to the data as Monte Carlo
  adds it: the rod's non-repeatable deflection (:mod:`calibrate.rod_slip`, ``priors.rod_slip``) and the robot's
  own unmodelled error at the campaign's poses (``priors.robot_floor_mm``, one
  :class:`~calibrate.simulate.RobotFloor` per draw).

On the validation configurations (base and tool refitted: the projection ``P`` off their 9 columns) the error
of the identified model is ``e = P J_v (E A y - xi) + P n`` (``E`` picks the kinematic parameters, ``n`` the
instrument noise). Its mean square is exact in the Gaussian parts (traces of the propagated covariances) and
averaged over ``draws`` values of ``r`` (stratified over its prior), of the compliance's shape and of the
validation configurations; the mean / max / median of the per-point error norms, and the 5-95 % band of a
campaign's mean error, have no closed form and come from the same draws of the linear model, which cost
milliseconds. The error budget follows :mod:`calibrate.predict`: *deflection* = this method minus the true
rod's compliance, *slip* = the true rod's with the rod's slip minus without it, *identification* = the latter minus
the true robot's own model, *noise* = the latter (:mod:`calibrate.budget`).

Not modelled (Monte Carlo, :mod:`calibrate.predict`, has them): the campaign's joint angles are the planned
ones (the true robot stops within the alignment tolerance elsewhere), and second-order terms of the robot's
errors and of the compensation computed from the identified model.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method

from .campaign import Fixture
from .compensations import deflection_basis
from .estimate import Selection
from .identify import free_parameters
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .observations import Observations, noise_covariance
from .params import INTERNAL_SCALE, PRIOR_SCALE, ParamInfo, apply, catalogue
from .budget import budget_shares
from .predict import VALIDATION_ROD, AccuracySummary, Priors
from .rod import Rod
from .unmodelled import campaign_offsets, validation_floor_offsets
from .errors import CalibrationError

__all__ = ["LinearCampaign", "ValidationDraws", "LinearPrediction", "linear_campaign", "linearisation_model",
           "validation_draws", "cached_validation_draws", "robot_prior", "compliance_draws", "predict_linear",
           "KINEMATIC_KINDS", "Draws", "random_parts", "exact_mean_square"]

#: the parameters the validation keeps from the identification (base and tool are refitted)
KINEMATIC_KINDS = ("dtheta", "a", "alpha", "d", "beta", "c")


@dataclass(frozen=True)
class _FitTerms:
    """What :meth:`LinearCampaign.scatter` and :meth:`LinearCampaign.weak` need of the fit of the columns
    ``cols`` (P,) bool: their Jacobian ``J`` (3N, p), its pseudo-inverse (p, 3N), the fixture uncertainty's
    variance ``a`` (p,) and the noise's per unit variance ``b`` (p,) of each parameter [internal units^2]."""

    cols: np.ndarray
    J: np.ndarray
    pinv: np.ndarray
    a: np.ndarray
    b: np.ndarray


@dataclass(frozen=True)
class LinearCampaign:
    """The planned campaign's linear model.

    J : (3N, P) Jacobian of the ball centres in {W} [mm per internal unit] w.r.t. the free parameters;
    J_kin : (3N, K) w.r.t. every kinematic parameter (the truth's errors); kin_of_free : (P,) index into the
    K kinematic parameters of each free one, -1 for base / tool; Sigma : (3N, 3N) device noise and fixture
    uncertainty [mm^2]; B : (3N, 18) ball-centre offsets per entry of ``C_F`` (row-major) and ``C_g`` [mm per
    mm/N, mm per mm/g0]; prior_scale : (P,) physical size of each free parameter [internal units]; free :
    their names; device_noise_mm : the device noise in ``Sigma`` (1 sigma per axis) [mm]
    """

    J: np.ndarray
    J_kin: np.ndarray
    kin_of_free: np.ndarray
    Sigma: np.ndarray
    B: np.ndarray
    prior_scale: np.ndarray
    free: tuple
    device_noise_mm: float

    def __post_init__(self) -> None:
        m, P = self.J.shape
        if self.J_kin.shape[0] != m or self.Sigma.shape != (m, m) or self.B.shape != (m, 18):
            raise ValueError(f"inconsistent shapes: J {self.J.shape}, J_kin {self.J_kin.shape}, Sigma "
                             f"{self.Sigma.shape}, B {self.B.shape}")
        if self.kin_of_free.shape != (P,) or self.prior_scale.shape != (P,):
            raise ValueError(f"kin_of_free / prior_scale must have shape ({P},)")

    def kinematic_map(self, K: int) -> np.ndarray:
        """(K, P) ``E``: picks the identified kinematic parameters (of the ``K``) out of the free ones."""
        E = np.zeros((K, self.J.shape[1]))
        k = np.nonzero(self.kin_of_free >= 0)[0]
        E[self.kin_of_free[k], k] = 1.0
        return E

    @property
    def is_c(self) -> np.ndarray:
        """(P,) bool: the joint compliances among the free parameters."""
        return np.array([nm.startswith("c_") for nm in self.free])

    def scatter(self, y: np.ndarray, cols: np.ndarray | None = None) -> np.ndarray:
        """The residual scatter [mm] (D,) of the plain least-squares fit of the columns ``cols`` (all by default)
        to each row of ``y`` (D, 3N), per degree of freedom, as identify estimates its noise level."""
        terms = self._terms(cols)
        r = y - (y @ terms.pinv.T) @ terms.J.T
        dof = max(terms.J.shape[0] - terms.J.shape[1], 1)
        return np.maximum(np.sqrt(np.sum(r ** 2, axis=1) / dof), 1e-6)

    def weak(self, noise_mm: np.ndarray, cols: np.ndarray | None = None) -> np.ndarray:
        """(D, P) which parameters identify regularises at each residual scatter ``noise_mm`` (D,): sandwich
        standard error of the fit of ``cols`` (``noise_mm`` in place of the device noise, and the fixture
        uncertainty) above the parameter's physical size (False outside ``cols``)."""
        terms = self._terms(cols)
        out = np.zeros((len(noise_mm), self.J.shape[1]), bool)
        out[:, terms.cols] = terms.a + np.asarray(noise_mm)[:, None] ** 2 * terms.b > self.prior_scale[terms.cols] ** 2
        return out

    def _terms(self, cols: np.ndarray | None) -> _FitTerms:
        """The noise-independent terms of :meth:`scatter` and :meth:`weak` for the columns ``cols``, computed
        once per column set (a campaign uses two: all, and all but the joint compliances)."""
        P = self.J.shape[1]
        if cols is None:
            cols = np.ones(P, bool)
        else:                                        # a bool mask or column indices; a copy of the caller's
            mask = np.zeros(P, bool)
            mask[np.asarray(cols)] = True
            cols = mask
        key = cols.tobytes()
        if key not in self._terms_cache:
            J = self.J[:, cols]
            A0 = np.linalg.pinv(J)
            fix = self.Sigma - self.device_noise_mm ** 2 * np.eye(self.Sigma.shape[0])
            self._terms_cache[key] = _FitTerms(cols, J, A0, np.einsum("ij,jk,ik->i", A0, fix, A0, optimize=True),
                                               np.sum(A0 ** 2, axis=1))
        return self._terms_cache[key]

    @cached_property
    def _terms_cache(self) -> dict:
        return {}

    def gains(self, y: np.ndarray, rough: bool, passes: int = 6) -> np.ndarray:
        """``A = G J^T`` (D, P, 3N) per campaign ``y`` (D, 3N): the identified parameters' response to the data
        (``G`` of :meth:`inverse_normals`)."""
        return _right(self.inverse_normals(y, rough, passes), self.J.T)

    def inverse_normals(self, y: np.ndarray, rough: bool, passes: int = 6) -> np.ndarray:
        """``G = (J^T J + L^T L)^-1`` (D, P, P) per campaign ``y`` (D, 3N), so that ``G J^T y`` are the identified
        parameters: the weak ones regularised at their start value (prior rows ``noise / physical size``) as
        identify does: with a rod to compensate (``rough``) the first pass holds the joint compliances and judges
        the others at its scatter; then each pass fits with the priors so far, takes its residual scatter as the
        noise level and regularises what is weak at it (a prior, once given, stays), up to ``passes``."""
        weak = np.zeros((y.shape[0], self.J.shape[1]), bool)
        if rough and self.is_c.any():
            cols = ~self.is_c
            weak |= self.weak(self.scatter(y, cols), cols)
        noise = self.scatter(y)
        dof = max(self.J.shape[0] - self.J.shape[1], 1)
        for _ in range(passes):
            weak |= self.weak(noise)
            r = y - self._fit(y, self._normal(weak, noise)) @ self.J.T
            noise = np.maximum(np.sqrt(np.sum(r ** 2, axis=1) / dof), 1e-6)
            if not (self.weak(noise) & ~weak).any():
                break
        return np.linalg.inv(self._bounded(y, weak, noise))

    def kinematic_rows(self, G: np.ndarray, K: int) -> np.ndarray:
        """``E G`` (D, K, P) for a stack ``G`` (D, P, ...): the rows of the free kinematic parameters placed at
        their index among the ``K`` (zero rows for those not free), without ``K x P`` products."""
        out = np.zeros((G.shape[0], K) + G.shape[2:])
        k = np.nonzero(self.kin_of_free >= 0)[0]
        out[:, self.kin_of_free[k]] = G[:, k]
        return out

    @cached_property
    def JtJ_kin(self) -> np.ndarray:
        """``J^T J_kin`` (P, K): the free parameters' normal equations' right-hand side per truth error."""
        return self.J.T @ self.J_kin

    @cached_property
    def JtSigmaJ(self) -> np.ndarray:
        """``J^T Sigma J`` (P, P): the normal equations' right-hand side's covariance under the noise."""
        return self.J.T @ self.Sigma @ self.J

    def _bounded(self, y: np.ndarray, weak: np.ndarray, noise: np.ndarray) -> np.ndarray:
        """The normal matrices (D, P, P) with identify's bounds: a joint compliance the fit would make negative
        (an uncompensated rod's deflection pulls the wrist's that way) stays at its start value 0 (the bounded
        solver's active set)."""
        at_bound = np.zeros_like(weak)
        for _ in range(4):
            M = self._normal(weak, noise, at_bound)
            low = np.zeros_like(weak)
            low[:, self.is_c] = self._fit(y, M)[:, self.is_c] < -1e-9
            if not (low & ~at_bound).any():
                break
            at_bound |= low
        return M

    def _normal(self, weak: np.ndarray, noise: np.ndarray, pinned: np.ndarray | None = None) -> np.ndarray:
        """``J^T J + diag(lambda)`` per draw (D, P, P): the priors of the weak parameters, and a stiff one
        holding the ``pinned`` at their start value."""
        lam = np.where(weak, (noise[:, None] / self.prior_scale) ** 2, 0.0)
        JtJ = self._JtJ
        if pinned is not None:
            lam = np.where(pinned, 1e10 * float(np.abs(np.diag(JtJ)).max()), lam)
        M = np.repeat(JtJ[None], lam.shape[0], axis=0)
        i = np.arange(JtJ.shape[0])
        M[:, i, i] += lam
        return M

    @cached_property
    def _JtJ(self) -> np.ndarray:
        return self.J.T @ self.J

    def _fit(self, y: np.ndarray, M: np.ndarray) -> np.ndarray:
        """The identified parameters (D, P) from the data ``y`` (D, 3N) with the normal matrices ``M``."""
        return np.linalg.solve(M, (y @ self.J)[:, :, None])[:, :, 0]


def _kin_infos(n: int) -> list[ParamInfo]:
    return [i for i in catalogue(n) if i.kind in KINEMATIC_KINDS]


def _campaign_observations(robot, model: ModelParams, plan_q: dict, fixture: Fixture, rod: Rod):
    keys = sorted(plan_q)
    q = np.concatenate([plan_q[j] for j in keys])
    group = np.concatenate([np.full(len(plan_q[j]), j) for j in keys])
    Ts = {int(j): fixture.transform(j) for j in keys}
    F = np.array([Ts[int(j)][:3, :3] @ fixture.force_D_N for j in group])
    fr, _ = ball_positions(robot, model, q, rod, force_W_N=F)
    return Observations(q, fr.pW, F, rod, group, None, Ts)


def linearisation_model(robot, tool_mm, base, priors: Priors) -> ModelParams:
    """The nominal robot with the prior's mean joint compliance (joints 2..n), the base ``base``."""
    c = np.concatenate([[0.0], np.full(robot.n - 1, float(np.mean(priors.joint_compliance)))])
    return ModelParams.nominal(robot, tool_mm).with_(c=c, base=np.asarray(base, float))


def linear_campaign(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                    priors: Priors = Priors()) -> LinearCampaign:
    """The linear model of the campaign planned as ``plan_q`` ({position: (k, n) [rad]}) with the rod
    ``reference`` (its mass, centre of mass and tool) on the nominal robot; raises
    :class:`~calibrate.errors.CalibrationError` where :func:`identify` would (unidentifiable parameters)."""
    model = linearisation_model(robot, reference.tool_mm, base, priors)
    obs = _campaign_observations(robot, model, plan_q, fixture, Rod.of(reference))
    positions = [j for j in sorted(set(obs.group.tolist())) if not np.allclose(obs.fixture_T[j], np.eye(4))]
    infos = catalogue(robot.n, positions)
    free, _ = free_parameters(robot, obs, apply(model, infos, np.zeros(len(infos))),
                              Selection(infos, reference.tool_mm, positions))
    fr, tau = obs.balls(robot, model)
    free_infos = [infos[k] for k in free]
    J = position_jacobian(fr, tau, free_infos, model.base, obs.group).reshape(-1, len(free))
    kin = _kin_infos(robot.n)
    J_kin = position_jacobian(fr, tau, kin, model.base, obs.group).reshape(-1, len(kin))
    names = [i.name for i in kin]
    kin_of_free = np.array([names.index(i.name) if i.name in names else -1 for i in free_infos])
    B = deflection_basis(robot, model, obs.q_rad, obs.force_W_N, obs.rod).reshape(-1, 18)
    Sigma = noise_covariance(obs, priors.device_noise_mm, priors.fixture_sigma)
    scale = np.array([PRIOR_SCALE[i.unit] * INTERNAL_SCALE[i.unit] for i in free_infos])
    return LinearCampaign(J, J_kin, kin_of_free, Sigma, B, scale, tuple(i.name for i in free_infos),
                          float(priors.device_noise_mm))


@dataclass(frozen=True)
class ValidationDraws:
    """The validation sets of the draws (as :func:`calibrate.predict` simulates them: random configurations
    within 60 % of the limits, the short validation rod), base and tool refitted.

    PJ : (D, 3M, K) the projected Jacobian ``P J_v`` w.r.t. the kinematic parameters [mm per internal unit];
    Q : (D, 3M, 9) orthonormal basis of the base / tool columns (``P = I - Q Q^T``); W : (D, K, K)
    ``(P J_v)^T P J_v``; q_rad : (D, M, n) the configurations [rad] (None: not kept; the robot floor is then
    isotropic scatter, :func:`_validation_sd`)
    """

    PJ: np.ndarray
    Q: np.ndarray
    W: np.ndarray
    q_rad: np.ndarray | None = None

    @property
    def points(self) -> int:
        return self.PJ.shape[1] // 3


def validation_draws(robot, priors: Priors, draws: int, seed: int = 0) -> ValidationDraws:
    """``draws`` validation sets of ``priors.validation_points`` configurations each (seeded: the same for
    every design)."""
    rng = np.random.default_rng([seed, 1])
    M, D = int(priors.validation_points), int(draws)
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    vq = rng.uniform(lo * 0.6, hi * 0.6, (D * M, robot.n))
    model = linearisation_model(robot, VALIDATION_ROD.tool_mm, np.zeros(6), priors)
    fr, tau = ball_positions(robot, model, vq, VALIDATION_ROD)
    kin = _kin_infos(robot.n)
    Jv = position_jacobian(fr, tau, kin, model.base).reshape(D, M * 3, len(kin))
    bt = [ParamInfo(f"base_{k}", "base_t", i, "mm") for i, k in enumerate("xyz")]
    bt += [ParamInfo(f"base_{k}", "base_r", i, "deg") for i, k in enumerate("abc")]
    bt += [ParamInfo(f"tool_{k}", "tool", i, "mm") for i, k in enumerate("xyz")]
    Jb = position_jacobian(fr, tau, bt, model.base).reshape(D, M * 3, len(bt))
    Q, _ = np.linalg.qr(Jb)
    PJ = Jv - Q @ (np.swapaxes(Q, 1, 2) @ Jv)
    return ValidationDraws(PJ, Q, np.swapaxes(PJ, 1, 2) @ PJ, vq.reshape(D, M, robot.n))


_CACHE: dict = {}


def cached_validation_draws(robot, priors: Priors, draws: int, seed: int = 0) -> ValidationDraws:
    """:func:`validation_draws`, kept for the process's next design (a study predicts many on one robot)."""
    key = (repr(robot), int(priors.validation_points), tuple(priors.joint_compliance), int(draws), int(seed))
    if key not in _CACHE:
        _CACHE.clear()                                  # one robot at a time: ~20 MB each
        _CACHE[key] = validation_draws(robot, priors, draws, seed)
    return _CACHE[key]


def robot_prior(robot, priors: Priors) -> tuple[np.ndarray, np.ndarray]:
    """Mean and standard deviation of the truth's kinematic errors [internal units] (K,) each, as
    :func:`calibrate.simulate.random_truth` draws them (the joint compliances uniform, from zero)."""
    par = set(robot.parallel_rows())
    s = float(priors.error_scale)
    lo, hi = (float(v) for v in priors.joint_compliance)
    mean, sd = [], []
    for info in _kin_infos(robot.n):
        i, k = info.index, info.kind
        sig = {"dtheta": 0.06 * s, "a": 0.5 * s, "alpha": 0.05 * s, "d": 0.0 if i in par else 0.5 * s,
               "beta": 0.05 * s if i in par else 0.0, "c": 0.0 if i == 0 else (hi - lo) / np.sqrt(12)}[k]
        mu = 0.0 if k != "c" or i == 0 else (lo + hi) / 2
        mean.append(mu * INTERNAL_SCALE[info.unit])
        sd.append(sig * INTERNAL_SCALE[info.unit])
    return np.array(mean), np.array(sd)


def compliance_draws(reference: RodCompliance, calc: RodCompliance | None, methods, priors: Priors,
                     draws: int, seed: int = 0) -> tuple[np.ndarray, dict, np.ndarray]:
    """(r (D,), {method: (D, 18) vec(C_true - C_file)}, true (D, 18) vec(C_true)): the true rod
    ``r S C S^T`` with ``r`` stratified over its prior and ``S = I + shape_sigma N``, and the files as
    :func:`calibrate.predict` makes them (meas: the true ``C_F`` within ``meas_sigma``, ``r_meas C_g``)."""
    rng = np.random.default_rng([seed, 2])
    D = int(draws)
    lo, hi = priors.r_rod
    r = lo + (hi - lo) * (rng.permutation(D) + rng.uniform(0, 1, D)) / D
    S = np.eye(3) + priors.shape_sigma * rng.standard_normal((D, 3, 3))
    CF = r[:, None, None] * S @ reference.C_F @ np.swapaxes(S, 1, 2)
    Cg = r[:, None, None] * S @ reference.C_g @ np.swapaxes(S, 1, 2)
    true = np.concatenate([CF.reshape(D, 9), Cg.reshape(D, 9)], axis=1)
    Sm = np.eye(3) + priors.meas_sigma * rng.standard_normal((D, 3, 3))
    r_meas = r * (1.0 + priors.meas_sigma * rng.standard_normal(D))
    meas = np.concatenate([(Sm @ CF @ np.swapaxes(Sm, 1, 2)).reshape(D, 9),
                           (r_meas[:, None, None] * reference.C_g).reshape(D, 9)], axis=1)
    files = {}
    for m in methods:
        if m is Method.NONE:
            files[m] = np.zeros((D, 18))
        elif m is Method.CALC:
            if calc is None:
                raise CalibrationError("method calc needs the closed-form compliance file", key="methods")
            files[m] = np.tile(np.concatenate([calc.C_F.ravel(), calc.C_g.ravel()]), (D, 1))
        elif m is Method.FEA:
            files[m] = np.tile(np.concatenate([reference.C_F.ravel(), reference.C_g.ravel()]), (D, 1))
        else:
            files[m] = meas
    return r, {m: true - f for m, f in files.items()}, true


@dataclass(frozen=True)
class LinearPrediction:
    """The linear predictor's result: one :class:`~calibrate.predict.AccuracySummary` per method (``replicates``
    = the draws), the nominal model's mean validation error [mm] and the validation noise floor's mean square
    [mm^2]."""

    summaries: list
    nominal_mean_mm: float
    ms_noise_mm2: float
    draws: int


@dataclass(frozen=True)
class Draws:
    """The random parts of the draws (:func:`random_parts`): the truth's errors xi (D, K) [internal units], the
    campaign noise eps (D, 3N) [mm] and the validation noise Pn (D, 3M) [mm], projected off base and tool."""

    xi: np.ndarray
    eps: np.ndarray
    Pn: np.ndarray


def random_parts(lc: LinearCampaign, vd: ValidationDraws, prior: tuple, priors: Priors, seed: int) -> Draws:
    """The draws' random parts (:class:`Draws`) from the generator ``[seed, 3]``: the truth's errors from
    ``prior`` = (mean, sd) (:func:`robot_prior`; a joint compliance uniform, the rest Gaussian), the campaign
    noise with the covariance ``lc.Sigma`` and the validation scatter of ``priors``."""
    mean, sd = prior
    rng = np.random.default_rng([seed, 3])
    D = vd.PJ.shape[0]
    is_c = (mean > 0)
    xi = mean + sd * np.where(is_c, np.sqrt(12.0) * (rng.uniform(size=(D, mean.size)) - 0.5),
                              rng.standard_normal((D, mean.size)))
    L = np.linalg.cholesky(lc.Sigma + 1e-18 * np.eye(lc.Sigma.shape[0]))
    eps = rng.standard_normal((D, L.shape[0])) @ L.T
    n = _validation_sd(priors, vd) * rng.standard_normal(vd.PJ.shape[:2])
    Pn = n - _mv(vd.Q, _mv(np.swapaxes(vd.Q, 1, 2), n))
    return Draws(xi, eps, Pn)


def _validation_sd(priors: Priors, vd: ValidationDraws) -> float:
    """Per-coordinate scatter of a validation point [mm]: the instrument's noise; when the validation
    configurations are not kept (``vd.q_rad`` None) also, added in quadrature, the robot's own unmodelled error
    (``priors.robot_floor_mm``, as an isotropic error whose projected mean norm is that floor). With them the
    floor is realised instead, the same :class:`~calibrate.simulate.RobotFloor` per draw in the campaign and on
    validation (:func:`_validation_floor`), as Monte Carlo does."""
    if vd.q_rad is not None:
        return float(priors.instrument_noise_mm)
    M, q = vd.points, vd.Q.shape[2]
    floor_sd = priors.robot_floor_mm / np.sqrt(8.0 / np.pi) / np.sqrt(max(3 * M - q, 1) / (3 * M))
    return float(np.hypot(priors.instrument_noise_mm, floor_sd))


def _validation_floor(robot, vd: ValidationDraws, priors: Priors, seed: int) -> np.ndarray | None:
    """(D, 3M) [mm] the robot floor on the validation points, projected (the campaign's floor of each draw,
    :func:`calibrate.unmodelled.validation_floor_offsets`); None without a floor or without the configurations."""
    if not priors.robot_floor_mm > 0 or vd.q_rad is None:
        return None
    key = (repr(robot), float(priors.robot_floor_mm), tuple(priors.joint_compliance), int(seed),
           hash(vd.q_rad.tobytes()))
    if key not in _VFLOOR:                            # the same for every design: kept for the next one
        model = linearisation_model(robot, VALIDATION_ROD.tool_mm, np.zeros(6), priors)
        _VFLOOR.clear()
        _VFLOOR[key] = validation_floor_offsets(robot, model, vd.q_rad, VALIDATION_ROD, vd.Q, priors.robot_floor_mm,
                                                seed)
    return _VFLOOR[key]


_VFLOOR: dict = {}


def exact_mean_square(lc: LinearCampaign, vd: ValidationDraws, G: np.ndarray, dC: np.ndarray, prior: tuple,
                      extra: np.ndarray | None = None, val_extra: np.ndarray | None = None) -> float:
    """Mean-square validation error [mm^2] (without the validation noise) over the draws' compliances,
    regularisations and validation sets, the Gaussian parts (campaign noise, the truth's spread) by their
    covariance: ``mean_d (|P J_v v_d|^2 + tr(W_d Cov_d)) / M`` (``W_d = (P J_v)^T P J_v``, ``vd.W``).

    G : (D, P, P) each draw's inverse normal matrix (:meth:`LinearCampaign.inverse_normals`; the gains are
    ``A = G J^T``, so ``E A Sigma A^T E^T = E G (J^T Sigma J) G E^T``: P x P products instead of 3N x 3N);
    dC : (D, 18) what the compensation leaves of each draw's compliance, ``vec(C_true - C_file)`` (the data's
    bias ``B dC``); prior : (mean, sd) (K,) of the truth's kinematic errors (:func:`robot_prior`); extra :
    (D, 3N) [mm] further bias of the data (the rod's slip, the robot floor at the campaign's poses; None: none);
    val_extra : (D, 3M) [mm] on validation (the robot floor there, projected; None: none)."""
    mean, sd = prior
    K = vd.PJ.shape[2]
    X = lc.kinematic_rows(G, K)                                       # (D, K, P) E G
    R = _right(X, lc.JtJ_kin) - np.eye(K)                             # E A J_kin - I
    bias = dC @ lc.B.T if extra is None else dC @ lc.B.T + extra
    v = _mv(X, bias @ lc.J) + R @ mean                                # (D, K) mean kinematic error
    ev = _mv(vd.PJ, v) if val_extra is None else _mv(vd.PJ, v) + val_extra
    bias = np.sum(ev ** 2, axis=1)
    cov = (R * sd ** 2) @ np.swapaxes(R, 1, 2) + _right(X, lc.JtSigmaJ) @ np.swapaxes(X, 1, 2)
    return float(np.mean(bias + np.sum(vd.W * cov, axis=(1, 2)))) / vd.points


def _right(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Every matrix of the stack ``A`` (D, i, j) times the one matrix ``B`` (j, k), as one GEMM -> (D, i, k) (2x
    faster than the broadcast ``A @ B``, which multiplies D small matrices)."""
    return (A.reshape(-1, A.shape[2]) @ B).reshape(A.shape[0], A.shape[1], B.shape[1])


def _mv(A: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Batched matrix times vector: (D, i, j) @ (D, j) -> (D, i)."""
    return (A @ x[:, :, None])[:, :, 0]


def _stats(e: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    norms = np.linalg.norm(e.reshape(e.shape[0], -1, 3), axis=2)
    return norms.mean(axis=1), norms.max(axis=1), np.median(norms, axis=1)


def predict_linear(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                   calc: RodCompliance | None = None, methods=(Method.NONE, Method.FEA, Method.MEAS),
                   priors: Priors = Priors(), draws: int = 256, seed: int = 0,
                   validation: ValidationDraws | None = None) -> LinearPrediction:
    """The predicted validation accuracy per method from the planned campaign (see the module docstring); the
    arguments as :func:`calibrate.predict.predict_accuracy`'s, ``draws`` of the linear model in place of
    its replicates; ``validation``: :func:`validation_draws` computed once for many designs."""
    methods = [Method.parse(m, "method") for m in methods]
    lc = linear_campaign(robot, plan_q, fixture, base, reference, priors)
    vd = validation if validation is not None else cached_validation_draws(robot, priors, draws, seed)
    D, K = vd.PJ.shape[0], vd.PJ.shape[2]
    mean, sd = robot_prior(robot, priors)
    rnd = random_parts(lc, vd, (mean, sd), priors, seed)
    _, dC, true = compliance_draws(reference, calc, methods, priors, D, seed)
    extra, floor_only = _unmodelled_data(robot, plan_q, fixture, base, reference, priors, true, seed, D, lc)
    E = lc.kinematic_map(K)
    M = vd.points
    ms_noise = _validation_sd(priors, vd) ** 2 * (3 * M - vd.Q.shape[2]) / M
    vf = _validation_floor(robot, vd, priors, seed)
    Pn = rnd.Pn if vf is None else rnd.Pn + vf                        # validation scatter: noise and floor
    ms_clean = ms_noise if vf is None else ms_noise + float(np.mean(np.sum(vf ** 2, axis=1))) / M
    y_robot = rnd.xi @ lc.J_kin.T + rnd.eps + extra
    G_true = lc.inverse_normals(y_robot, rough=True)
    ms_true = exact_mean_square(lc, vd, G_true, np.zeros((D, 18)), (mean, sd), extra, vf) + ms_noise
    ms_no_slip = float("nan")
    if priors.rod_slip:                                               # the slip's own share of the budget
        G_ns = lc.inverse_normals(rnd.xi @ lc.J_kin.T + rnd.eps + floor_only, rough=True)
        ms_no_slip = exact_mean_square(lc, vd, G_ns, np.zeros((D, 18)), (mean, sd), floor_only, vf) + ms_noise
    out = []
    for m in methods:
        y = y_robot + dC[m] @ lc.B.T
        G = lc.inverse_normals(y, rough=m is not Method.NONE)
        delta = _mv(G, y @ lc.J) @ E.T - rnd.xi
        means, maxs, medians = _stats(_mv(vd.PJ, delta) + Pn)
        ms = exact_mean_square(lc, vd, G, dC[m], (mean, sd), extra, vf) + ms_noise
        out.append(AccuracySummary(m, float(means.mean()), float(maxs.mean()), float(medians.mean()),
                                   float(np.percentile(means, 5)), float(np.percentile(means, 95)),
                                   float(np.sqrt(ms)), budget_shares(ms, ms_true, ms_clean, ms_no_slip), D, 0,
                                   tuple(float(v) for v in means)))
    nominal = _stats(Pn - _mv(vd.PJ, rnd.xi))[0]
    return LinearPrediction(out, float(nominal.mean()), float(ms_clean), D)


def _unmodelled_data(robot, plan_q, fixture, base, reference, priors: Priors, true: np.ndarray, seed: int, D: int,
                     lc: LinearCampaign) -> tuple[np.ndarray, np.ndarray]:
    """(D, 3N) [mm] twice: what neither model nor compensation describes in the campaign's data per draw — the
    rod's slip and the robot floor at its poses — and the robot floor alone (zeros where the priors have none)."""
    zero = np.zeros((D, lc.J.shape[0]))
    if not priors.rod_slip and priors.robot_floor_mm <= 0:
        return zero, zero
    model = linearisation_model(robot, reference.tool_mm, base, priors)
    obs = _campaign_observations(robot, model, plan_q, fixture, Rod.of(reference))
    floor = (campaign_offsets(robot, model, obs, replace(priors, rod_slip=0.0), true, seed)
             if priors.robot_floor_mm > 0 else zero)
    slip = (campaign_offsets(robot, model, obs, replace(priors, robot_floor_mm=0.0), true, seed)
            if priors.rod_slip else zero)                 # each from its own generator: their sum is the draws' both
    return slip + floor, floor
