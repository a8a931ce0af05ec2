"""Vectorised kinematics of a serial robot with joint compliance, and static joint torques.

Model (contract): ``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)``,
``theta_i = q_i + theta_offset_i + dtheta_i + c_i tau_i``; ``p^W = T_0^W T_0^n [tool, 1]``, ``T_0^W = T(base)``.
Extension (``rodlab.calibration/2``): a periodic error of the joint reading, ``+ h1s_i (sin q_i - m1s_i) + h1c_i
(cos q_i - m1c_i) + h2s_i (sin 2q_i - m2s_i) + h2c_i (cos 2q_i - m2c_i)`` (gear or encoder eccentricity), zero
unless identified; the ``m`` are each term's mean over the calibration's readings, so that the term has no
constant part there and the geometric rows alone stay close to the best geometric model.
Internal units: mm, rad, N, N m; arrays over N configurations.
"""
from __future__ import annotations

import numbers
import warnings
from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.frames import pose_to_matrix

from .rod import Rod

__all__ = ["ModelParams", "Frames", "HARMONICS", "harmonic_basis", "harmonic_reference", "forward", "static_torques",
           "ball_positions"]

#: the periodic joint-error terms, in the column order of :attr:`ModelParams.h`: name -> (order, sin or cos)
HARMONICS = {"h1s": (1, np.sin), "h1c": (1, np.cos), "h2s": (2, np.sin), "h2c": (2, np.cos)}


def harmonic_basis(q_rad: np.ndarray) -> np.ndarray:
    """sin q, cos q, sin 2q, cos 2q of every joint reading, shape=(N, n, 4) from q shape=(N, n) [rad]."""
    return np.stack([f(k * q_rad) for k, f in HARMONICS.values()], axis=-1)


def harmonic_reference(q_rad: np.ndarray, joints) -> np.ndarray:
    """:attr:`ModelParams.h_ref` for the readings ``q_rad`` (N, n): each term's mean for the 1-based ``joints``,
    zeros elsewhere."""
    ref = np.zeros((np.shape(q_rad)[1], len(HARMONICS)))
    for j in joints:
        ref[j - 1] = harmonic_basis(np.asarray(q_rad)[:, j - 1:j]).mean(axis=0)[0]
    return ref


@dataclass(frozen=True)
class ModelParams:
    """Actual values of every model parameter (internal units).

    theta_offset, alpha, beta [rad], d, a [mm] : shape=(n,); c [rad/(N m)] : shape=(n,);
    base : pose of {0} in {W} [mm, deg] (contract pose vector), shape=(6,); tool : ball centre in {n} [mm];
    h : periodic joint-angle errors [rad], shape=(n, 4), columns :data:`HARMONICS` (None: zeros);
    h_ref : the mean of each term's function over the calibration's readings, shape=(n, 4) (None: zeros): the
        model adds ``h * (f(q) - h_ref)``
    """

    theta_offset: np.ndarray
    d: np.ndarray
    a: np.ndarray
    alpha: np.ndarray
    beta: np.ndarray
    c: np.ndarray
    base: np.ndarray
    tool: np.ndarray
    h: np.ndarray | None = None
    h_ref: np.ndarray | None = None

    def __post_init__(self):
        n = len(self.theta_offset)
        for name in ("h", "h_ref"):
            v = getattr(self, name)
            v = np.zeros((n, len(HARMONICS))) if v is None else np.asarray(v, float)
            if v.shape != (n, len(HARMONICS)):
                raise ValueError(f"ModelParams.{name}: expected shape ({n}, {len(HARMONICS)}) (joints x harmonic "
                                 f"terms), got {v.shape}")
            object.__setattr__(self, name, v)

    @classmethod
    def nominal(cls, robot, tool_mm, base=None) -> "ModelParams":
        n = robot.n
        return cls(np.deg2rad(robot.theta_offset_deg), robot.d_mm.astype(float), robot.a_mm.astype(float),
                   np.deg2rad(robot.alpha_deg), np.deg2rad(robot.beta_deg), np.zeros(n),
                   np.zeros(6) if base is None else np.asarray(base, float), np.asarray(tool_mm, float))

    def with_(self, **kw) -> "ModelParams":
        return replace(self, **kw)


@dataclass
class Frames:
    """Kinematic quantities per configuration (N) and joint (n), in {0} unless said.

    T : shape=(N, n + 1, 4, 4), frames 0..n; z_prev, o_prev : joint axes and origins (frames i-1);
    xA : x axis after Rz(theta) (the a_i and alpha_i directions); yB : y axis after Rx(alpha) (beta_i);
    o_i : origins of frames i; p0 : ball centre in {0}, shape=(N, 3); pW : in {W}; R_W0 : shape=(3, 3);
    theta : joint angles of the rows [rad]; q : the joint readings they came from [rad], shape=(N, n);
    harmonic : the periodic terms' functions of the readings less their reference, shape=(N, n, 4), or None
        when the model has no periodic terms
    """

    T: np.ndarray
    z_prev: np.ndarray
    o_prev: np.ndarray
    xA: np.ndarray
    yB: np.ndarray
    o_i: np.ndarray
    p0: np.ndarray
    pW: np.ndarray
    R_W0: np.ndarray
    t_W0: np.ndarray
    theta: np.ndarray
    q: np.ndarray
    harmonic: np.ndarray | None = None


def _rows(theta, d, a, alpha, beta):
    """Row transforms, shape=(N, n, 4, 4), and the intermediate rotation after Rz(theta) Rx(alpha)."""
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.broadcast_to(np.cos(alpha), theta.shape), np.broadcast_to(np.sin(alpha), theta.shape)
    cb, sb = np.cos(beta), np.sin(beta)
    N, n = theta.shape
    T = np.zeros((N, n, 4, 4))
    # Rz(t) Rx(al) Ry(b)
    RzRx = np.zeros((N, n, 3, 3))
    RzRx[..., 0, 0], RzRx[..., 0, 1], RzRx[..., 0, 2] = ct, -st * ca, st * sa
    RzRx[..., 1, 0], RzRx[..., 1, 1], RzRx[..., 1, 2] = st, ct * ca, -ct * sa
    RzRx[..., 2, 0], RzRx[..., 2, 1], RzRx[..., 2, 2] = 0.0, sa, ca
    Ry = np.zeros((n, 3, 3))
    Ry[:, 0, 0], Ry[:, 0, 2], Ry[:, 1, 1], Ry[:, 2, 0], Ry[:, 2, 2] = cb, sb, 1.0, -sb, cb
    T[..., :3, :3] = RzRx @ Ry[None]
    T[..., 0, 3] = a * ct
    T[..., 1, 3] = a * st
    T[..., 2, 3] = d
    T[..., 3, 3] = 1.0
    return T, RzRx


def forward(params: ModelParams, q_rad: np.ndarray, tau_Nm: np.ndarray | None = None) -> Frames:
    """Frames of every configuration; ``q_rad`` shape=(N, n) [rad]; ``tau_Nm`` shape=(N, n) or None."""
    q = np.atleast_2d(q_rad)
    N, n = q.shape
    theta = q + params.theta_offset[None, :]
    harmonic = None
    if params.h.any() or params.h_ref.any():
        harmonic = harmonic_basis(q) - params.h_ref[None]
        theta = theta + np.einsum("nk,Nnk->Nn", params.h, harmonic)
    if tau_Nm is not None:
        theta = theta + params.c[None, :] * tau_Nm
    rows, RzRx = _rows(theta, params.d, params.a, params.alpha, params.beta)
    T = np.zeros((N, n + 1, 4, 4))
    T[:, 0] = np.eye(4)
    for i in range(n):
        T[:, i + 1] = T[:, i] @ rows[:, i]
    R_prev = T[:, :n, :3, :3]
    z_prev = R_prev[..., :, 2]
    o_prev = T[:, :n, :3, 3]
    ct, st = np.cos(theta), np.sin(theta)
    xA = R_prev[..., :, 0] * ct[..., None] + R_prev[..., :, 1] * st[..., None]
    yB = (R_prev @ RzRx[..., :, 1:2])[..., 0]
    o_i = T[:, 1:, :3, 3]
    p0 = (T[:, n, :3, :3] @ params.tool[:, None])[..., 0] + T[:, n, :3, 3]
    TB = pose_to_matrix(params.base)
    R_W0, t_W0 = TB[:3, :3], TB[:3, 3]
    pW = p0 @ R_W0.T + t_W0
    return Frames(T, z_prev, o_prev, xA, yB, o_i, p0, pW, R_W0, t_W0, theta, q, harmonic)


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a x b over the last axis (broadcast), without np.cross's per-call overhead."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a1 * b2 - a2 * b1
    out[..., 1] = a2 * b0 - a0 * b2
    out[..., 2] = a0 * b1 - a1 * b0
    return out


def static_torques(robot, fr: Frames, rod: Rod | None = None, force_W_N: np.ndarray | None = None) -> np.ndarray:
    """Static joint torques [N m], shape=(N, n): gravity on the links and the rod (``rod``: its mass and centre of
    mass; None: no rod) plus the contact force ``force_W_N`` in {W} [N].

    The torque about joint i (axis z_{i-1} through o_{i-1}) of every load beyond it; the joint's gearbox
    deflects in the direction of that torque (theta = ... + c tau). With each load's force F_k at c_k on link
    k: ``tau_i = z_i . (M_i - o_i x S_i)``, ``M_i = sum_{k>=i} c_k x F_k``, ``S_i = sum_{k>=i} F_k`` (suffix
    sums over the links), vectorised over configurations and joints.
    """
    N = fr.T.shape[0]
    n = robot.n
    g0 = np.asarray(robot.gravity_base, float)                       # m/s^2 in {0}
    # loads per link: the link's mass at its COM (in frame k + 1), the rod at its COM (in {T} = {n} axes at
    # the ball) and the contact force at the ball (both on the last link)
    R, t = fr.T[:, 1:, :3, :3], fr.T[:, 1:, :3, 3]                    # (N, n, 3, 3), (N, n, 3)
    c = (R @ np.asarray(robot.com_mm, float)[:, :, None])[..., 0] + t
    F = np.broadcast_to(np.asarray(robot.mass_kg, float)[:, None] * g0, (N, n, 3))
    M = cross3(c, F)                                                 # moment about {0}'s origin [N mm]
    S = F.copy()
    if rod is not None and rod.mass_kg > 0:
        cr = fr.p0 + fr.T[:, n, :3, :3] @ rod.com_T_mm
        Fr = np.broadcast_to(rod.mass_kg * g0, (N, 3))
        M[:, n - 1] += cross3(cr, Fr)
        S[:, n - 1] += Fr
    if force_W_N is not None:
        F0 = np.broadcast_to(np.atleast_2d(force_W_N) @ fr.R_W0, (N, 3))   # {W} -> {0}
        M[:, n - 1] += cross3(fr.p0, F0)
        S[:, n - 1] += F0
    Msum = np.cumsum(M[:, ::-1], axis=1)[:, ::-1]                      # sum over k >= i
    Ssum = np.cumsum(S[:, ::-1], axis=1)[:, ::-1]
    return np.einsum("mij,mij->mi", fr.z_prev, Msum - cross3(fr.o_prev, Ssum)) * 1e-3   # N mm -> N m


def ball_positions(robot, params: ModelParams, q_rad, rod: Rod | None = None, *legacy, force_W_N=None,
                   iterations: int = 2, **deprecated) -> tuple[Frames, np.ndarray]:
    """Frames with the joint compliance solved consistently (torques at the deflected pose), and the torques.

    rod : the rod on the flange (:class:`~rodlab.calibrate.rod.Rod`; its weight loads the joints: only its mass and
        centre of mass are read, the ball is at ``params.tool``), or None for none; force_W_N : contact force on the
        ball in {W} [N], (N, 3) or (3,), or None (by keyword). The old forms with the rod's mass and centre of mass
        as two numbers still work, with a DeprecationWarning: ``ball_positions(robot, params, q, mass, com[, force[,
        iterations]])``, the same with ``force_W_N=`` / ``iterations=`` by keyword, and ``rod_mass_kg=`` /
        ``rod_com_T_mm=``.
    """
    if deprecated or legacy or isinstance(rod, numbers.Real):
        rod, force_W_N, iterations = _legacy_load(rod, legacy, force_W_N, iterations, deprecated)
    q = np.atleast_2d(q_rad)
    tau = np.zeros_like(q)
    fr = forward(params, q, tau)
    if np.any(params.c != 0):
        for _ in range(iterations):
            tau = static_torques(robot, fr, rod, force_W_N)
            fr = forward(params, q, tau)
    else:
        tau = static_torques(robot, fr, rod, force_W_N)
    return fr, tau


def _legacy_load(rod, legacy: tuple, force_W_N, iterations, deprecated: dict):
    """The arguments of the old signature ``ball_positions(robot, params, q, rod_mass_kg, rod_com_T_mm, force_W_N,
    iterations)`` as (rod, force, iterations) of the new one."""
    unknown = set(deprecated) - {"rod_mass_kg", "rod_com_T_mm"}
    if unknown:
        raise TypeError(f"ball_positions() got unexpected keyword arguments {sorted(unknown)}")
    if legacy and not isinstance(rod, numbers.Real):
        raise TypeError("ball_positions(robot, params, q, rod, ...): the force and iterations go by keyword "
                        "(force_W_N=, iterations=)")
    if len(legacy) > 3 or (len(legacy) > 1 and force_W_N is not None) or (len(legacy) > 2 and iterations != 2):
        raise TypeError("ball_positions(): the old form takes mass, com, force_W_N, iterations once each")
    warnings.warn("ball_positions(..., rod_mass_kg, rod_com_T_mm, ...) is deprecated: pass the rod as a Rod "
                  "(rodlab.calibrate.Rod.rigid(tool_mm, mass_kg, com_T_mm))", DeprecationWarning, stacklevel=3)
    if isinstance(rod, numbers.Real):                  # positional: (mass, com, force, iterations)
        mass, com = float(rod), (legacy[0] if legacy else deprecated.get("rod_com_T_mm"))
        force_W_N = legacy[1] if len(legacy) > 1 else force_W_N
        iterations = legacy[2] if len(legacy) > 2 else iterations
    else:
        mass, com = deprecated.get("rod_mass_kg", 0.0), deprecated.get("rod_com_T_mm")
    com = np.zeros(3) if com is None else com
    return Rod.rigid(np.zeros(3), mass, com), force_W_N, iterations
