"""The planned campaign's linear model: the identification linearised around the robot's nominal model.

:func:`linear_campaign` gives the campaign's Jacobians (the free parameters' and every kinematic parameter's), the
noise's covariance and the compensation's basis (:class:`LinearCampaign`); its :meth:`~LinearCampaign.
inverse_normals` reproduce identify's regularisation of the weak parameters per campaign, vectorised over many
draws. :mod:`calibrate.predict_linear` predicts the validation accuracy from it.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from rodlab.core.compliance import RodCompliance

from .campaign import Fixture
from .compensations import deflection_basis
from .estimate import Selection
from .identify import free_parameters
from .jacobian import position_jacobian
from .kinematics import ModelParams, ball_positions
from .observations import Observations, noise_covariance
from .params import INTERNAL_SCALE, PRIOR_SCALE, ParamInfo, apply, catalogue
from .predict import Priors
from .rod import Rod

__all__ = ["LinearCampaign", "linear_campaign", "linearisation_model", "campaign_observations", "kinematic_infos",
           "KINEMATIC_KINDS", "right_product"]

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
        return right_product(self.inverse_normals(y, rough, passes), self.J.T)

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


def kinematic_infos(n: int) -> list[ParamInfo]:
    return [i for i in catalogue(n) if i.kind in KINEMATIC_KINDS]


def campaign_observations(robot, model: ModelParams, plan_q: dict, fixture: Fixture, rod: Rod):
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
    obs = campaign_observations(robot, model, plan_q, fixture, Rod.of(reference))
    positions = [j for j in sorted(set(obs.group.tolist())) if not np.allclose(obs.fixture_T[j], np.eye(4))]
    infos = catalogue(robot.n, positions)
    free, _ = free_parameters(robot, obs, apply(model, infos, np.zeros(len(infos))),
                              Selection(infos, reference.tool_mm, positions))
    fr, tau = obs.balls(robot, model)
    free_infos = [infos[k] for k in free]
    J = position_jacobian(fr, tau, free_infos, model.base, obs.group).reshape(-1, len(free))
    kin = kinematic_infos(robot.n)
    J_kin = position_jacobian(fr, tau, kin, model.base, obs.group).reshape(-1, len(kin))
    names = [i.name for i in kin]
    kin_of_free = np.array([names.index(i.name) if i.name in names else -1 for i in free_infos])
    B = deflection_basis(robot, model, obs.q_rad, obs.force_W_N, obs.rod).reshape(-1, 18)
    Sigma = noise_covariance(obs, priors.device_noise_mm, priors.fixture_sigma)
    scale = np.array([PRIOR_SCALE[i.unit] * INTERNAL_SCALE[i.unit] for i in free_infos])
    return LinearCampaign(J, J_kin, kin_of_free, Sigma, B, scale, tuple(i.name for i in free_infos),
                          float(priors.device_noise_mm))


def right_product(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Every matrix of the stack ``A`` (D, i, j) times the one matrix ``B`` (j, k), as one GEMM -> (D, i, k) (2x
    faster than the broadcast ``A @ B``, which multiplies D small matrices)."""
    return (A.reshape(-1, A.shape[2]) @ B).reshape(A.shape[0], A.shape[1], B.shape[1])


