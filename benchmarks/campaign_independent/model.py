"""Independent forward model of a MultiCal campaign (written from /work/shared/contract and the paper only).

Conventions (see README.md in this folder):
  pose [x,y,z,a,b,c] (mm, deg) -> T = Trans(x,y,z) * Rx(a) Ry(b) Rz(c)
  DH row:  T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)
           theta_i = q_i + offset_i + dtheta_i + c_i * tau_i (+ optional extra joint-angle error e_i(q))
  tau_i:   static torque about z_{i-1} (N m) of the loads distal to joint i: link weights (tx90.toml masses,
           COMs in frame i), rod weight (mass, COM in {T}), contact force on the ball.  Sign: positive when the
           load turns the joint in its positive sense -> compliance deflects the joint in the load's direction.
           Solved at the deflected pose (fixed-point iteration).
  ball:    p^W = T(chi_B) T_0^6 [tool, 1] + R_WT (C_g g^T + C_F F^T)   (deflection added; rodlab compensates Eq. 11)
           {T}: axes of frame {6} (rod twist is part of dtheta_6), origin at the ball centre.
  reading: x^D_j = T(chi_j)^-1 p^W  (+ 3 um noise), chi_j the TRUE pose of {D_j} in {W} = {D_3}.
"""
import math
import os
import tomllib
import numpy as np

G0 = 9.80665
CONTRACT = os.path.join(os.environ.get("RODLAB_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared")), "contract")  # rodlab: the shared folder beside the repository


def rotx(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def roty(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def rotz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def pose_R(abc_deg):
    a, b, c = np.radians(abc_deg)
    return rotx(a) @ roty(b) @ rotz(c)


def pose_T(p):
    T = np.eye(4)
    T[:3, :3] = pose_R(p[3:6])
    T[:3, 3] = p[:3]
    return T


def T_pose(T):
    """inverse of pose_T (XYZ moving-axes Euler, b in [-90, 90])."""
    R = T[:3, :3]
    b = math.asin(max(-1.0, min(1.0, R[0, 2])))
    a = math.atan2(-R[1, 2], R[2, 2])
    c = math.atan2(-R[0, 1], R[0, 0])
    return [float(T[0, 3]), float(T[1, 3]), float(T[2, 3]), math.degrees(a), math.degrees(b), math.degrees(c)]


def rotvec(w):
    """rotation matrix of a rotation vector (rad)."""
    th = np.linalg.norm(w)
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def load_robot_nominal(path=f"{CONTRACT}/tx90.toml"):
    with open(path, "rb") as f:
        t = tomllib.load(f)
    J = t["joint"]
    r = dict(
        offset_deg=np.array([j["theta_offset_deg"] for j in J], float),
        dtheta_deg=np.zeros(6),
        d_mm=np.array([j["d_mm"] for j in J], float),
        a_mm=np.array([j["a_mm"] for j in J], float),
        alpha_deg=np.array([j["alpha_deg"] for j in J], float),
        beta_deg=np.array([j["beta_deg"] for j in J], float),
        c_rad_per_Nm=np.zeros(6),
        mass_kg=np.array([j["mass_kg"] for j in J], float),
        com_mm=np.array([j["com_mm"] for j in J], float),
        limits_deg=np.array([j["limits_deg"] for j in J], float),
        gravity_base=np.array(t["gravity_base"], float),
    )
    return r


def copy_robot(r):
    return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in r.items()}


def _row(theta, d, a, alpha, beta):
    """batched DH-Hayati row, theta (N,), returns (N,4,4)."""
    N = theta.shape[0]
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = math.cos(alpha), math.sin(alpha)
    # Rz(theta) Tz(d) Tx(a) Rx(alpha)
    T = np.zeros((N, 4, 4))
    T[:, 0, 0] = ct
    T[:, 0, 1] = -st * ca
    T[:, 0, 2] = st * sa
    T[:, 0, 3] = a * ct
    T[:, 1, 0] = st
    T[:, 1, 1] = ct * ca
    T[:, 1, 2] = -ct * sa
    T[:, 1, 3] = a * st
    T[:, 2, 1] = sa
    T[:, 2, 2] = ca
    T[:, 2, 3] = d
    T[:, 3, 3] = 1.0
    if beta != 0.0:
        Ry = np.eye(4)
        Ry[:3, :3] = roty(beta)
        T = T @ Ry
    return T


def chain(robot, theta):
    """theta (N,6) rad -> frames (N,7,4,4): F[:,0]=I (base), F[:,i] = frame i."""
    N = theta.shape[0]
    F = np.zeros((N, 7, 4, 4))
    F[:, 0] = np.eye(4)
    al = np.radians(robot["alpha_deg"])
    be = np.radians(robot["beta_deg"])
    for i in range(6):
        F[:, i + 1] = F[:, i] @ _row(theta[:, i], robot["d_mm"][i], robot["a_mm"][i], al[i], be[i])
    return F


def torques(robot, F, tool, rod_mass, rod_com_T, force_base, mass_scale=None, com_override=None):
    """static joint torques (N,6) N m. force_base (N,3) N (force on the ball, base frame) or None."""
    N = F.shape[0]
    g = robot["gravity_base"]
    masses = robot["mass_kg"] if mass_scale is None else robot["mass_kg"] * mass_scale
    coms = robot["com_mm"] if com_override is None else com_override
    # positions of point loads (mm, base) and forces (N, base)
    pts, fs = [], []
    for k in range(6):
        p = F[:, k + 1, :3, :3] @ coms[k] + F[:, k + 1, :3, 3]
        pts.append((k + 1, p, np.broadcast_to(masses[k] * g, (N, 3))))
    R6 = F[:, 6, :3, :3]
    o6 = F[:, 6, :3, 3]
    p_rod = R6 @ (np.asarray(tool) + np.asarray(rod_com_T)) + o6
    pts.append((6, p_rod, np.broadcast_to(rod_mass * g, (N, 3))))
    if force_base is not None:
        p_ball = R6 @ np.asarray(tool) + o6
        pts.append((6, p_ball, force_base))
    tau = np.zeros((N, 6))
    for i in range(6):  # joint i+1, axis z of frame i
        z = F[:, i, :3, 2]
        o = F[:, i, :3, 3]
        for (link, p, f) in pts:
            if link >= i + 1:
                r = (p - o) * 1e-3
                tau[:, i] += np.einsum("ij,ij->i", z, np.cross(r, f))
    return tau


def flange(robot, q_deg, tool, rod_mass, rod_com_T, force_base_fn=None, extra_theta=None, n_iter=6,
           mass_scale=None, com_override=None, c_fn=None):
    """solve theta with compliance at the deflected pose. Returns frames (N,7,4,4), theta, tau.
    force_base_fn(F) -> (N,3) force on the ball in base (depends on base orientation only, F unused)
    extra_theta: (N,6) rad added to theta (non-compliance joint errors).
    c_fn(tau) -> (N,6) rad compliance deflection (default c*tau)."""
    q = np.radians(np.atleast_2d(q_deg))
    base_theta = q + np.radians(robot["offset_deg"] + robot["dtheta_deg"])
    if extra_theta is not None:
        base_theta = base_theta + extra_theta
    theta = base_theta.copy()
    tau = np.zeros_like(theta)
    for _ in range(n_iter):
        F = chain(robot, theta)
        fb = force_base_fn(F) if force_base_fn is not None else None
        tau = torques(robot, F, tool, rod_mass, rod_com_T, fb, mass_scale, com_override)
        defl = c_fn(tau) if c_fn is not None else robot["c_rad_per_Nm"] * tau
        theta = base_theta + defl
    F = chain(robot, theta)
    return F, theta, tau
