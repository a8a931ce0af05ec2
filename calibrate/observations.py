"""What the identification fits (:class:`Observations`: joint angles, measured ball centres in {W}, loads), its
noise model (:func:`noise_covariance`: device noise plus each recorded clamping pose's uncertainty) and the
rigid registration of the base (and the tool) that starts every fit."""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.frames import abc_rate_axes, pose_to_matrix, skew, matrix_to_pose

from .campaign import Campaign, Fixture
from .errors import CalibrationError
from .kinematics import ModelParams, ball_positions
from .rod import Rod

__all__ = ["Observations", "campaign_observations", "register_base", "register_base_and_tool", "noise_covariance"]

log = logging.getLogger(__name__)


@dataclass
class Observations:
    """What the identification fits: joint angles, measured ball centres in {W}, and the loads.

    q_rad (N, n); x_W_mm (N, 3); force_W_N (N, 3) contact force on the ball in {W}; rod the rod the points were
    measured with (:class:`~rodlab.calibrate.rod.Rod`: its weight loads the joints), or None for no payload;
    group (N,) clamping position of each point (fixture uncertainty correlation), labels (N,);
    sigma_mm (N, 3) stated standard uncertainty of each measured coordinate [mm] (instrument points), or None
    for one noise level for all; temp_C (N,) temperature of each point [degC] or None (thermal compensation);
    noise_shape_W (N, 3, 3) covariance in {W} of each point per unit variance of the device's readings [-] (raw
    readings through a non-orthogonal device), or None; pose_cov {group: (6, 6) covariance of the recorded
    pose [x, y, z, a, b, c] of that clamping position, (mm, deg) units} where the fixture file states one
    """

    q_rad: np.ndarray
    x_W_mm: np.ndarray
    force_W_N: np.ndarray
    rod: Rod | None = None
    group: np.ndarray | None = None
    labels: list | None = None
    fixture_T: dict | None = None          # group -> 4x4 pose of {D_j} in {W}
    x_D_mm: np.ndarray | None = None
    sigma_mm: np.ndarray | None = None
    temp_C: np.ndarray | None = None
    noise_shape_W: np.ndarray | None = None
    pose_cov: dict | None = None

    def __post_init__(self):
        if self.rod is not None and not isinstance(self.rod, Rod):
            raise TypeError(f"Observations.rod must be a Rod or None, got {type(self.rod).__name__} (Rod.of(compliance) "
                            f"or Rod.rigid(tool_mm, mass_kg, com_T_mm))")
        if self.sigma_mm is not None and np.shape(self.sigma_mm) != np.shape(self.x_W_mm):
            raise ValueError(f"sigma_mm must have the shape of x_W_mm {np.shape(self.x_W_mm)}, got "
                             f"{np.shape(self.sigma_mm)}")
        if self.temp_C is not None and np.shape(self.temp_C) != (np.shape(self.x_W_mm)[0],):
            raise ValueError(f"temp_C must have shape ({np.shape(self.x_W_mm)[0]},), got {np.shape(self.temp_C)}")
        if self.noise_shape_W is not None and np.shape(self.noise_shape_W) != (np.shape(self.x_W_mm)[0], 3, 3):
            raise ValueError(f"noise_shape_W must have shape ({np.shape(self.x_W_mm)[0]}, 3, 3), got "
                             f"{np.shape(self.noise_shape_W)}")

    def balls(self, robot, params: ModelParams):
        """The model's frames and joint torques at these points (:func:`~.kinematics.ball_positions`) under the
        loads they were measured with: the rod's weight and the contact forces."""
        return ball_positions(robot, params, self.q_rad, self.rod, force_W_N=self.force_W_N)

    def subset(self, keep: np.ndarray) -> "Observations":
        """The points where the boolean mask ``keep`` (N,) is true, every per-point field with them."""
        keep = np.asarray(keep, bool)
        if keep.shape != (self.x_W_mm.shape[0],):
            raise ValueError(f"keep must have shape ({self.x_W_mm.shape[0]},), got {keep.shape}")

        def cut(a):
            return None if a is None else np.asarray(a)[keep]
        return replace(self, q_rad=self.q_rad[keep], x_W_mm=self.x_W_mm[keep], force_W_N=self.force_W_N[keep],
                       group=cut(self.group), x_D_mm=cut(self.x_D_mm), sigma_mm=cut(self.sigma_mm),
                       temp_C=cut(self.temp_C), noise_shape_W=cut(self.noise_shape_W),
                       labels=None if self.labels is None else [lab for lab, k in zip(self.labels, keep) if k])


def campaign_observations(camp: Campaign, fix: Fixture, rod: Rod | RodCompliance) -> Observations:
    """Eq. 2: device readings to {W}; the contact force of each point in {W} (Eq. 12): the springs' at its
    readings for a raw campaign read with a device that states them, else the fixture's constant one; the
    rod (a :class:`~rodlab.calibrate.rod.Rod` or its compliance file) travels with them."""
    if camp.x_D_mm is None:
        raise CalibrationError("this campaign gives the sensors' raw readings (s1_mm, s2_mm, s3_mm): give the "
                               "device file that converts them (--device DEV.device.json)", path=camp.path,
                               key="s1_mm")
    missing = sorted(set(camp.position.tolist()) - set(fix.poses))
    if missing:
        raise CalibrationError(f"clamping position(s) {missing} of the campaign are not in the fixture file "
                               f"(it has {sorted(fix.poses)})", path=fix.path, key="positions")
    xW = np.empty((camp.n, 3))
    F = np.empty((camp.n, 3))
    shape = None if camp.noise_shape_D is None else np.empty((camp.n, 3, 3))
    force_D = np.broadcast_to(fix.force_D_N, (camp.n, 3)) if camp.force_D_N is None else camp.force_D_N
    for j in np.unique(camp.position):
        T = fix.transform(int(j))
        R = T[:3, :3]
        m = camp.position == j
        xW[m] = camp.x_D_mm[m] @ R.T + T[:3, 3]
        F[m] = force_D[m] @ R.T
        if shape is not None:
            shape[m] = R @ camp.noise_shape_D[m] @ R.T
    pose_cov = None if fix.pose_cov is None else {j: c for j, c in fix.pose_cov.items() if j in set(camp.position)}
    rod = Rod.of(rod) if isinstance(rod, RodCompliance) else rod
    return Observations(np.deg2rad(camp.q_deg), xW, F, rod, camp.position.copy(), camp.labels(),
                        {int(j): fix.transform(int(j)) for j in np.unique(camp.position)},
                        camp.x_D_mm.copy(), temp_C=None if camp.temp_C is None else camp.temp_C.copy(),
                        noise_shape_W=shape, pose_cov=pose_cov)


def register_base(robot, params: ModelParams, obs: Observations) -> np.ndarray:
    """Base pose [mm, deg] by rigid registration (Kabsch) of nominal ball positions to the measured ones."""
    fr, _ = ball_positions(robot, params.with_(base=np.zeros(6)), obs.q_rad)
    P, Q = fr.p0, obs.x_W_mm
    pc, qc = P.mean(0), Q.mean(0)
    H = (P - pc).T @ (Q - qc)
    U, S, Vt = np.linalg.svd(H)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T))])
    R = Vt.T @ D @ U.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = qc - R @ pc
    return matrix_to_pose(T)


def register_base_and_tool(robot, params: ModelParams, obs: Observations, iterations: int = 100,
                           tol_mm: float = 1e-6) -> tuple[np.ndarray, np.ndarray, float]:
    """Base pose and tool point from scratch, for instrument points whose tool is only roughly known.

    Alternates the rigid registration of the nominal points (:func:`register_base`) with the linear
    least-squares tool given the base (``R_B^T (x - b) - p_n = R_n t``). Returns (base [mm, deg] shape=(6,),
    tool in {n} [mm] shape=(3,), rms distance [mm]); the better of this and the given tool is kept.
    """
    n = robot.n

    def rms_of(p):
        fr, _ = ball_positions(robot, p, obs.q_rad)
        return float(np.sqrt(np.mean(np.sum((fr.pW - obs.x_W_mm) ** 2, axis=1))))

    p = params.with_(base=register_base(robot, params, obs))
    best = (p.base, p.tool, rms_of(p))
    prev = np.inf
    for _ in range(iterations):
        fr, _ = ball_positions(robot, p.with_(base=np.zeros(6)), obs.q_rad)
        TB = pose_to_matrix(p.base)
        lhs = (obs.x_W_mm - TB[:3, 3]) @ TB[:3, :3] - fr.T[:, n, :3, 3]        # R_B^T (x - b) - p_n
        A = fr.T[:, n, :3, :3].reshape(-1, 3)
        tool, *_ = np.linalg.lstsq(A, lhs.reshape(-1), rcond=None)
        p = p.with_(tool=tool)
        p = p.with_(base=register_base(robot, p, obs))
        r = rms_of(p)
        if r < best[2]:
            best = (p.base, p.tool, r)
        if abs(prev - r) < tol_mm:
            break
        prev = r
    return best


def noise_covariance(obs: Observations, noise_mm: float, fixture_sigma=(0.01, 0.002)) -> np.ndarray:
    """Covariance of the measured points [mm^2], shape=(3N, 3N): device noise plus the uncertainty of each
    recorded clamping pose, correlated among the points of a position. ``fixture_sigma`` = (standard
    uncertainty of each recorded x, y, z [mm], of each recorded angle a, b, c [deg]): the angles' uncertainty
    reaches the orientation through the rates of ``Rx(a) Ry(b) Rz(c)`` (:func:`rodlab.core.frames.abc_rate_axes`),
    larger along one axis near b = +-90 deg.

    With per-point uncertainties (``obs.sigma_mm``) the noise of each coordinate is proportional to its stated
    sigma, scaled so that its rms over the data set is ``noise_mm`` (pass the stated rms to use them as they
    are, an estimated level to keep only their shape). With raw readings (``obs.noise_shape_W``) ``noise_mm``
    is each sensor reading's noise, propagated through the device's axes.

    A clamping position whose fixture file states its pose covariance (``obs.pose_cov``, fitted from probes)
    uses it instead of ``fixture_sigma``; ``fixture_sigma = (0, 0)`` leaves every pose's uncertainty out (the
    device-only covariance)."""
    N = obs.x_W_mm.shape[0]
    if obs.sigma_mm is not None:
        s = obs.sigma_mm.reshape(-1)
        S = np.diag((s * noise_mm / np.sqrt(np.mean(s ** 2))) ** 2)
    elif obs.noise_shape_W is not None:
        S = np.zeros((3 * N, 3 * N))
        for i in range(N):
            S[3 * i:3 * i + 3, 3 * i:3 * i + 3] = noise_mm ** 2 * obs.noise_shape_W[i]
    else:
        S = noise_mm ** 2 * np.eye(3 * N)
    if obs.group is not None and obs.fixture_T is not None and any(fixture_sigma):
        default = np.diag([fixture_sigma[0]] * 3 + [fixture_sigma[1]] * 3) ** 2
        stated = obs.pose_cov or {}
        for j, T in obs.fixture_T.items():
            if np.allclose(T, np.eye(4)):
                continue                                   # the world position defines {W}
            m = np.nonzero(obs.group == j)[0]
            G = pose_point_jacobian(obs.x_W_mm[m], T).reshape(3 * m.size, 6)
            rows = (3 * m[:, None] + np.arange(3)).ravel()
            S[np.ix_(rows, rows)] += G @ stated.get(j, default) @ G.T
    return S


def pose_point_jacobian(x_W_mm: np.ndarray, T: np.ndarray) -> np.ndarray:
    """shape=(k, 3, 6): how points ``x_W_mm`` (k, 3) read in a device frame of pose ``T`` (4x4) move per unit
    change of its recorded pose [x, y, z, a, b, c] (per mm, per deg): a translation moves them along, the angles
    turn them about the origin through the rates of Rx(a) Ry(b) Rz(c), omega x d = -skew(d) omega."""
    d = np.asarray(x_W_mm, float) - T[:3, 3]
    G = np.zeros((d.shape[0], 3, 6))
    G[:, :, :3] = np.eye(3)
    G[:, :, 3:] = -skew(d) @ abc_rate_axes(T[:3, :3]) * np.deg2rad(1.0)
    return G
