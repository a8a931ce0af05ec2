"""Is physics missing? One test of an identification's residuals against the noise model, shared by
``rodlab calibrate`` (its trust verdict) and ``rodlab diagnose --campaign`` (its "consistent" verdict).

The noise model is the one the identification's standard errors use (:func:`calibrate.identify.noise_covariance`):
device noise per reading plus the uncertainty of each recorded clamping pose, correlated among the points of
a position. The residuals are whitened with it and projected off the identified parameters' Jacobian (the
generalised-least-squares refit: what the parameters can absorb is not evidence of missing physics); their
sum of squares is chi-square with ``3 N - P`` degrees of freedom if the model is complete. Physics is missing
when the tail probability is below :data:`P_MISSING`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .jacobian import position_jacobian

from .observations import noise_covariance
__all__ = ["ResidualTest", "residual_test", "P_MISSING", "BIRGE_MATERIAL"]

#: tail probability below which the residuals are not noise (the diagnosers' likelihood-ratio level too)
P_MISSING = 1e-3
#: Birge ratio sqrt(chi2 / dof) above which missing physics matters for the parameters: below it the scatter
#: the model leaves out is at most about the noise model's own (sqrt(1.5^2 - 1) = 1.1 times), so its pull on
#: each parameter is of the order of the standard errors, which are computed from the residuals' scatter anyway
BIRGE_MATERIAL = 1.5
#: below this p-value (and above :data:`P_MISSING`) the residuals are at the edge of the noise model: not a
#: finding, but not worded as "consistent with noise" either (a new user read "consistent ... p = 0.0038" as a
#: contradiction)
P_EDGE = 1e-2
#: degrees of freedom below which the residuals say nothing about the noise (a trial's 8 points for 24 parameters:
#: reduced chi-square 0.00 over 1 degree of freedom, 'consistent with noise' and 'complete? yes')
MIN_TEST_DOF = 5


@dataclass(frozen=True)
class ResidualTest:
    """The residual chi-square test of one identification.

    chi2 : whitened, projected sum of squares [-]; dof : ``3 N - P``; reduced : chi2 / dof; p_value : P(X > chi2)
    for X ~ chi-square(dof); noise_mm : device noise assumed [mm]; fixture_sigma : clamping-pose uncertainty
    assumed ([mm], [deg]); missing : p_value < :data:`P_MISSING`; clamping : the noise model has clamping poses
    (a MultiCal campaign); source : what the noise is of otherwise (``instrument``, ``seat``, ``ball bar``)
    """

    chi2: float
    dof: int
    reduced: float
    p_value: float
    noise_mm: float
    fixture_sigma: tuple
    missing: bool
    clamping: bool = True
    source: str = "instrument"             # what the noise is of, without clamping poses (the wording)
    poses_stated: bool = False             # the fixture file states each pose's covariance (rodlab.fixture/2)
    stated_range_mm: tuple = ()            # (smallest, largest) sigma where each point states its own [mm]

    @property
    def birge(self) -> float:
        return float(np.sqrt(max(self.reduced, 0.0)))

    @property
    def material(self) -> bool:
        return self.missing and self.birge > BIRGE_MATERIAL

    @property
    def testable(self) -> bool:
        """Enough degrees of freedom (:data:`MIN_TEST_DOF`) for the residuals to say anything about the noise."""
        return self.dof >= MIN_TEST_DOF

    @property
    def wording(self) -> str:
        """How the residuals compare with the noise model, in words: ``NOT noise``, ``slightly above noise``, ``at
        the edge of the noise model (not significant at p < 0.001)``, ``consistent with noise``; ``not testable``
        with fewer than :data:`MIN_TEST_DOF` degrees of freedom."""
        if not self.testable:
            return f"not testable ({self.dof} degree(s) of freedom: the fit can absorb any noise)"
        if self.material:
            return "NOT noise"
        if self.missing:
            return "slightly above noise"
        if self.p_value < P_EDGE:
            return f"at the edge of the noise model (not significant at p < {P_MISSING:g})"
        return "consistent with noise"

    def noise_phrase(self) -> str:
        """``17.6 um``, or where each point states its sigma ``as each point states it (3.7-42.0 um, rms 17.6
        um)``: the test weighs each point by its own (a trial: a Birge ratio of 47 beside 238 um / 17.6 um = 13.5
        had read as a contradiction)."""
        if self.stated_range_mm:
            lo, hi = self.stated_range_mm
            return (f"as each point states it ({lo * 1e3:.1f}-{hi * 1e3:.1f} um, rms {self.noise_mm * 1e3:.1f} um; "
                    f"each point weighed by its own)")
        return f"{self.noise_mm * 1e3:.1f} um"

    def to_dict(self) -> dict:
        """The test as the calibration result and the diagnosis report record it."""
        return {"reduced_chi2": self.reduced, "dof": self.dof, "p_value": self.p_value, "birge_ratio": self.birge,
                "physics_missing": self.missing, "material": self.material}

    def describe(self) -> str:
        """One sentence: the statistic, the noise model and the verdict."""
        head = (f"reduced chi-square {self.reduced:.2f} over {self.dof} degrees of freedom (p = {self.p_value:.2g}) "
                f"under the noise model: ")
        if not self.clamping:
            per = "per reading" if "length" in self.source else "per coordinate"
            return head + f"{self.source} {self.noise_phrase()} {per}"
        poses = ("as the fixture file states them" if self.poses_stated else
                 f"{self.fixture_sigma[0]:g} mm / {self.fixture_sigma[1]:g} deg")
        return head + f"device {self.noise_mm * 1e3:.1f} um per reading, clamping poses {poses}"


def whitened_projection(r_mm: np.ndarray, J: np.ndarray, L: np.ndarray) -> np.ndarray:
    """Residuals ``r_mm`` (3N,) whitened by the Cholesky factor ``L`` (3N, 3N) of their covariance and
    projected off ``J`` (3N, P)."""
    r = np.linalg.solve(L, r_mm)
    Jw = np.linalg.solve(L, J)
    return r - Jw @ np.linalg.lstsq(Jw, r, rcond=None)[0]


def residual_test(robot, res, obs, noise_mm: float, fixture_sigma=(0.01, 0.002)) -> ResidualTest:
    """The test of ``res`` (a :class:`calibrate.identify.CalibrationResult` of ``obs``) with device noise
    ``noise_mm`` [mm] and clamping-pose uncertainty ``fixture_sigma`` ([mm], [deg])."""
    from scipy.special import chdtrc                                    # heavy (scipy.special, ~0.15 s)


    if not (np.isfinite(noise_mm) and noise_mm > 0):
        raise ValueError(f"noise_mm must be > 0, got {noise_mm!r}")
    N = obs.x_W_mm.shape[0]
    fr, tau = obs.balls(robot, res.params)
    free = [i for i in res.infos if i.name in res.free]
    J = position_jacobian(fr, tau, free, res.params.base, obs.group).reshape(3 * N, -1)
    L = np.linalg.cholesky(noise_covariance(obs, noise_mm, fixture_sigma))
    e = whitened_projection(res.residuals_mm.reshape(-1), J, L)
    dof = max(3 * N - J.shape[1], 1)
    chi2 = float(e @ e)
    p = float(chdtrc(dof, chi2))
    sig = getattr(obs, "sigma_mm", None)
    stated = (float(np.min(sig)), float(np.max(sig))) if sig is not None and np.ptp(sig) > 0 else ()
    return ResidualTest(chi2, dof, chi2 / dof, p, float(noise_mm), tuple(fixture_sigma), p < P_MISSING,
                        obs.group is not None, poses_stated=bool(getattr(obs, "pose_cov", None)),
                        stated_range_mm=stated)
