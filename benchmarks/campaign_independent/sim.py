"""Independent MultiCal campaign simulator (written from /work/shared/contract, the paper and the shared examples
only; no rodlab code).  Conventions: README.md beside this file.

usage:  python sim.py [OUTDIR]          -> writes OUTDIR/cases/<name>/ for every case of CASES below
"""
import csv
import json
import math
import os
import shutil
import sys

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from model import (G0, chain, copy_robot, flange, load_robot_nominal, pose_R, pose_T, rotvec, rotz, T_pose,
                   torques)

EX = os.path.join(os.environ.get("RODLAB_SHARED", os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..", "shared")), "examples")  # rodlab: the shared folder beside the repository
ROD_FILE = f"{EX}/campaign-null/rod1.compliance.json"
F_D = np.array([1.10, 1.25, 1.05])  # contact force in {D_j} (contract default / examples)

NOISE_DEVICE_MM = 0.003
NOISE_VAL_MM = 0.02
FIX_ERR_MM, FIX_ERR_DEG = 0.01, 0.002


# ----------------------------------------------------------------------------------------------- lab layout
def R_vertical_device():
    """rotation R0 (device -> base) that puts the device's (1,1,1)/sqrt3 on the base's +z (sensor axes 54.7 deg
    from the plumb line, pointing upwards)."""
    n = np.ones(3) / math.sqrt(3)
    ax = np.cross(n, [0, 0, 1.0])
    ang = math.acos(n[2])
    return rotvec(ax / np.linalg.norm(ax) * ang)


def make_lab(rng, n_pos):
    """device frames {D_j} in the robot base frame.  Position 3 is the centre of the fixture and {W}."""
    R0 = R_vertical_device()
    rD = rng.uniform(720, 880)
    psi = math.radians(rng.uniform(-150, 150))
    h = rng.uniform(0, 180)
    c3 = np.array([rD * math.cos(psi), rD * math.sin(psi), h])
    radial = np.array([math.cos(psi), math.sin(psi), 0.0])
    tang = np.array([-math.sin(psi), math.cos(psi), 0.0])
    u, v = rng.uniform(80, 130), rng.uniform(130, 220)
    corners = [(u, v), (u, -v), (-u, v), (-u, -v), (0, v), (0, -v), (u, 0), (-u, 0)]
    others = [corners[i] for i in rng.permutation(4)] + [corners[i] for i in 4 + rng.permutation(4)]
    offs = {}
    labels = [j for j in range(1, n_pos + 1) if j != 3]
    for j, (a, b) in zip(labels, others):
        offs[j] = c3 + a * radial + b * tang
    offs[3] = c3
    T_BD = {}
    for j, o in offs.items():
        T = np.eye(4)
        T[:3, :3] = rotz(math.radians(rng.uniform(-180, 180))) @ R0
        T[:3, 3] = o
        T_BD[j] = T
    return T_BD


# ----------------------------------------------------------------------------------------------- true robot
def draw_robot(rng, scale=None):
    r = load_robot_nominal()
    s = rng.uniform(1.2, 2.4) if scale is None else scale
    r["dtheta_deg"] = rng.normal(0, 0.05, 6) * s
    r["d_mm"] = r["d_mm"] + rng.normal(0, 0.35, 6) * s
    r["a_mm"] = r["a_mm"] + rng.normal(0, 0.35, 6) * s
    r["alpha_deg"] = r["alpha_deg"] + np.r_[rng.normal(0, 0.035, 5) * s, 0.0]
    r["beta_deg"] = np.array([0.0, rng.normal(0, 0.035) * s, 0, 0, 0, 0])
    r["c_rad_per_Nm"] = np.r_[0.0, rng.uniform(3e-6, 6e-6, 5)]
    # last row's d, a errors are folded into the tool (contract: they are tool parameters)
    r["d_mm"][5] = 100.0
    r["a_mm"][5] = 0.0
    return r, s


# ----------------------------------------------------------------------------------------------- physics
class Physics:
    """The true world of one case: robot, base, rod, fixture, and the effects."""

    def __init__(self, robot, T_WB, tool, rod, C_F, C_g, T_WD, effects):
        self.robot = robot
        self.T_WB = T_WB
        self.tool = np.asarray(tool, float)
        self.rod = rod
        self.C_F = np.asarray(C_F, float)
        self.C_g = np.asarray(C_g, float)
        self.T_WD = T_WD  # true device poses in {W}
        self.eff = {e["type"]: e for e in effects}

    # ---- joint-angle errors (not compliance)
    def extra_theta(self, q_deg, approach):
        q = np.radians(q_deg)
        ex = np.zeros_like(q)
        for key in ("periodic", "harmonic2"):
            e = self.eff.get(key)
            if e:
                K = e["joint"] - 1
                h = e.get("harmonic", 1 if key == "periodic" else 2)
                ex[:, K] += math.radians(e["amp_deg"]) * np.sin(h * q[:, K] + math.radians(e["phase_deg"]))
        e = self.eff.get("backlash")
        if e:
            K = e["joint"] - 1
            ex[:, K] += 0.5 * math.radians(e["lost_motion_deg"]) * approach[:, K]
        return ex

    def c_fn(self):
        e = self.eff.get("nonlinear_compliance")
        c = self.robot["c_rad_per_Nm"]
        if not e:
            return None
        Ks = [k - 1 for k in e["joints"]]
        ts = e["tau_s_Nm"]

        def f(tau):
            d = c * tau
            for K in Ks:
                d[:, K] = c[K] * tau[:, K] / (1.0 + np.abs(tau[:, K]) / ts)
            return d
        return f

    def loads(self, robot, F, tool, rod_mass, rod_com_T, fB, first_link):
        """point loads (position mm, force N, base) of links >= first_link, rod and contact force."""
        out = []
        g = robot["gravity_base"]
        masses = self.masses(robot)
        coms = self.coms(robot)
        for k in range(first_link, 7):
            p = np.einsum("nij,j->ni", F[:, k, :3, :3], coms[k - 1]) + F[:, k, :3, 3]
            out.append((p, np.broadcast_to(masses[k - 1] * g, p.shape)))
        R6, o6 = F[:, 6, :3, :3], F[:, 6, :3, 3]
        out.append((np.einsum("nij,j->ni", R6, tool + np.asarray(rod_com_T)) + o6,
                    np.broadcast_to(rod_mass * g, o6.shape)))
        if fB is not None:
            out.append((np.einsum("nij,j->ni", R6, tool) + o6, fB))
        return out

    def masses(self, robot):
        e = self.eff.get("mass_model")
        return robot["mass_kg"] * (np.asarray(e["mass_scale"]) if e else 1.0)

    def coms(self, robot):
        e = self.eff.get("mass_model")
        return robot["com_mm"] + (np.asarray(e["com_shift_mm"]) if e else 0.0)

    def frame_hook(self, robot, F, tool, rod_mass, rod_com_T, fB):
        e = self.eff.get("link_bending")
        if e:
            F = self._bend_forearm(robot, F, tool, rod_mass, rod_com_T, fB, e)
        e = self.eff.get("base_compliance")
        if e:
            loads = self.loads(robot, F, tool, rod_mass, rod_com_T, fB, first_link=1)
            M = np.zeros((F.shape[0], 3))
            for p, f in loads:
                M += np.cross(p * 1e-3, f)
            th = np.stack([M[:, 0] * e["c_x_rad_per_Nm"], M[:, 1] * e["c_y_rad_per_Nm"], np.zeros(len(M))], 1)
            for n in range(F.shape[0]):
                Rb = np.eye(4)
                Rb[:3, :3] = rotvec(th[n])
                F[n] = Rb @ F[n]
        return F

    def _bend_forearm(self, robot, F, tool, rod_mass, rod_com_T, fB, e):
        """forearm (frame 3 origin -> frame 4 origin, along z3) as a cantilever: Euler-Bernoulli bending under the
        loads beyond it (links 5, 6, rod, contact force) and its own weight (link 4's mass, spread uniformly)."""
        EI = e["EI_Nm2"]
        g = robot["gravity_base"]
        N = F.shape[0]
        A = F[:, 3, :3, 3] * 1e-3
        B = F[:, 4, :3, 3] * 1e-3
        L = np.linalg.norm(B - A, axis=1)
        u = (B - A) / L[:, None]
        loads = self.loads(robot, F, tool, rod_mass, rod_com_T, fB, first_link=5)
        w = self.masses(robot)[3] * g / L[:, None]  # N/m, link 4 spread along the forearm
        ns = 40
        Theta = np.zeros((N, 3))
        delta = np.zeros((N, 3))
        ds = L / ns
        for i in range(ns):
            s = (i + 0.5) * ds
            P = A + u * s[:, None]
            M = np.zeros((N, 3))
            for p, f in loads:
                M += np.cross(p * 1e-3 - P, f)
            M += ((L - s) ** 2 / 2)[:, None] * np.cross(u, w)
            Mp = M - np.einsum("ni,ni->n", M, u)[:, None] * u
            dTh = Mp / EI * ds[:, None]
            delta += np.cross(Theta + 0.5 * dTh, u) * ds[:, None]
            Theta += dTh
        out = F.copy()
        for n in range(N):
            D = np.eye(4)
            D[:3, :3] = rotvec(Theta[n])
            wpt = F[n, 4, :3, 3]
            D[:3, 3] = delta[n] * 1e3 + wpt - D[:3, :3] @ wpt
            for k in range(4, 7):
                out[n, k] = D @ F[n, k]
        return out

    def robot_at(self, t, temp, T0):
        """robot with thermal growth at time t / temperature temp (uniform growth of every link length)."""
        e = self.eff.get("thermal")
        if not e:
            return self.robot
        if e["driver"] == "time":
            eps = e["growth_ppm_per_s"] * 1e-6 * t
        else:
            eps = e["growth_ppm_per_K"] * 1e-6 * (temp - T0)
        r = copy_robot(self.robot)
        scope = e.get("scope", "links")
        if scope == "long":  # only the two long castings (upper arm a2, forearm d4)
            r["a_mm"][1] *= 1 + eps
            r["d_mm"][3] *= 1 + eps
        else:  # "links": every link length of the arm; "all": also the tool (see ball())
            r["d_mm"] = r["d_mm"] * (1 + eps)
            r["a_mm"] = r["a_mm"] * (1 + eps)
        return r

    def thermal_eps(self, t, temp, T0):
        e = self.eff["thermal"]
        return e["growth_ppm_per_s"] * 1e-6 * t if e["driver"] == "time" else \
            e["growth_ppm_per_K"] * 1e-6 * (temp - T0)

    # ---- the ball
    def ball(self, q_deg, pos, approach=None, t=None, temp=None, T0=None, tool=None, rod_mass=None,
             rod_com_T=None, contact=True, deflect=True):
        """true ball centre in {W} (N,3) and R_WT (N,3,3)."""
        q_deg = np.atleast_2d(q_deg)
        N = len(q_deg)
        tool = self.tool if tool is None else np.asarray(tool, float)
        rod_mass = self.rod["mass_kg"] if rod_mass is None else rod_mass
        rod_com_T = self.rod["com_T_mm"] if rod_com_T is None else rod_com_T
        if approach is None:
            approach = np.zeros((N, 6))
        RWB = self.T_WB[:3, :3]
        if contact:
            fW = np.array([self.T_WD[p][:3, :3] @ F_D for p in pos])
            fB = (RWB.T @ fW.T).T
        else:
            fB = None
        if "thermal" in self.eff and t is not None:
            scope_all = self.eff["thermal"].get("scope") == "all"
            outs = [self._ball1(self.robot_at(t[n], temp[n], T0), q_deg[n:n + 1], approach[n:n + 1],
                                tool * (1 + self.thermal_eps(t[n], temp[n], T0)) if scope_all else tool,
                                rod_mass, rod_com_T, None if fB is None else fB[n:n + 1], deflect)
                    for n in range(N)]
            return np.concatenate([o[0] for o in outs]), np.concatenate([o[1] for o in outs])
        return self._ball1(self.robot, q_deg, approach, tool, rod_mass, rod_com_T, fB, deflect)

    def _ball1(self, robot, q_deg, approach, tool, rod_mass, rod_com_T, fB, deflect):
        ex = self.extra_theta(q_deg, approach)
        hook = None
        if "link_bending" in self.eff or "base_compliance" in self.eff:
            hook = True
        # compliance solved at the deflected pose (model.flange), torques from this case's mass model
        e = self.eff.get("mass_model")
        Fr, th, tau = flange(robot, q_deg, tool, rod_mass, rod_com_T,
                             force_base_fn=(lambda F: fB) if fB is not None else None, extra_theta=ex,
                             mass_scale=(np.asarray(e["mass_scale"]) if e else None),
                             com_override=(self.coms(robot) if e else None), c_fn=self.c_fn())
        if hook:
            Fr = self.frame_hook(robot, Fr, tool, rod_mass, rod_com_T, fB)
        R6 = Fr[:, 6, :3, :3]
        p = np.einsum("nij,j->ni", R6, tool) + Fr[:, 6, :3, 3]
        if deflect:
            gT = np.einsum("nji,j->ni", R6, robot["gravity_base"] / G0)
            dT = gT @ self.C_g.T
            if fB is not None:
                fT = np.einsum("nji,nj->ni", R6, fB)
                dT = dT + fT @ self.C_F.T
            p = p + np.einsum("nij,nj->ni", R6, dT)
        pW = p @ self.T_WB[:3, :3].T + self.T_WB[:3, 3]
        RWT = np.einsum("ij,njk->nik", self.T_WB[:3, :3], R6)
        return pW, RWT

    # ---- the device
    def reading(self, pW, RWT, pos, rng_noise, noise=True):
        x = np.array([np.linalg.solve(self.T_WD[p], np.r_[pw, 1])[:3] for p, pw in zip(pos, pW)])
        e = self.eff.get("ball_shape")
        if e:
            r0 = 15.0
            ax = r0 + np.asarray(e["semi_axis_err_mm"])
            for n, p in enumerate(pos):
                RDT = self.T_WD[p][:3, :3].T @ RWT[n]
                M = RDT @ np.diag(ax ** 2) @ RDT.T
                h = np.sqrt(np.diag(M))  # support function along each device axis
                x[n] -= h - r0
        e = self.eff.get("device_axes")
        if e:
            U = device_axes_matrix(e["sensor2_x_deg"], e["sensor3_x_deg"], e["sensor3_y_deg"])
            x = x @ U.T
        e = self.eff.get("sensor_gain")
        if e:
            x = x * (1 + np.asarray(e["gain"]))
        if noise:
            x = x + rng_noise.normal(0, NOISE_DEVICE_MM, x.shape)
        return x


def device_axes_matrix(t2x, t3x, t3y):
    """rows = sensor axes in {D}: sensor 1 = x; sensor 2 in the xy-plane tilted by t2x towards x; sensor 3 tilted
    by t3x towards x and t3y towards y."""
    a2 = math.radians(t2x)
    u2 = np.array([math.sin(a2), math.cos(a2), 0.0])
    u3 = np.array([math.tan(math.radians(t3x)), math.tan(math.radians(t3y)), 1.0])
    u3 /= np.linalg.norm(u3)
    return np.array([[1.0, 0, 0], u2, u3])


# ----------------------------------------------------------------------------------------------- IK
def nominal_flange_pose(robot, q_deg):
    F = chain(robot, np.radians(np.atleast_2d(q_deg)) + np.radians(robot["offset_deg"]))
    return F[:, 6]


def ik_nominal(robot, T_target, rng, q_seeds, q1c):
    """numerical IK of the flange pose, restricted to the usual family (shoulder towards the target, elbow up)."""
    lo = np.array([q1c - 75, -30, 0, -180, -120, -200])
    hi = np.array([q1c + 75, 100, 145, 180, 120, 200])
    lim = robot["limits_deg"]
    lo, hi = np.maximum(lo, lim[:, 0]), np.minimum(hi, lim[:, 1])

    def res(q):
        T = nominal_flange_pose(robot, q)[0]
        return np.r_[T[:3, 3] - T_target[:3, 3], 400.0 * (T[:3, :3] - T_target[:3, :3]).ravel()]
    best = None
    for q0 in q_seeds:
        q0 = np.clip(q0, lo + 1e-3, hi - 1e-3)
        sol = least_squares(res, q0, bounds=(lo, hi), method="trf", xtol=1e-12, ftol=1e-12, gtol=1e-12,
                            max_nfev=300)
        if np.linalg.norm(sol.fun) > 1e-4:
            continue
        q = sol.x
        score = abs(q[3]) + abs(q[5]) * 0.5
        if best is None or score < best[0]:
            best = (score, q)
    return None if best is None else best[1]


def ik_refine(phys, q0, target_W, pos, approach=None, t=None, temp=None, T0=None, iters=8):
    """min-norm Gauss-Newton on the TRUE ball position (alignment on the device)."""
    q = np.array(q0, float)
    ap = None if approach is None else approach[None]
    tt = None if t is None else np.array([t])
    te = None if temp is None else np.array([temp])
    for _ in range(iters):
        p, _ = phys.ball(q[None], [pos], ap, tt, te, T0)
        r = target_W - p[0]
        if np.linalg.norm(r) < 1e-6:
            break
        J = np.zeros((3, 6))
        h = 1e-4
        for k in range(6):
            dq = q.copy()
            dq[k] += h
            pk, _ = phys.ball(dq[None], [pos], ap, tt, te, T0)
            J[:, k] = (pk[0] - p[0]) / h
        q = q + np.linalg.pinv(J) @ r
    return q


def plan_orientations(robot, T_BD, n_orient, rng, tool_nom, h_dev, max_tries=400):
    """random rod orientations reaching the datum of {D}: pipe II (x6) mostly downwards, pipe I free about it."""
    target = T_BD[:3, 3]
    got, Rs = [], []
    tries = 0
    q1c = math.degrees(math.atan2(-target[1], -target[0]))  # the arm reaches along -x1 for q2 > 0
    while len(got) < n_orient and tries < max_tries:
        tries += 1
        th = rng.uniform(5, 70) if rng.random() < 0.85 else rng.uniform(70, 115)
        az = rng.uniform(0, 2 * math.pi)
        th = math.radians(th)
        d = np.array([math.sin(th) * math.cos(az), math.sin(th) * math.sin(az), -math.cos(th)])
        a = np.cross(d, [0, 0, 1.0])
        a = a / np.linalg.norm(a) if np.linalg.norm(a) > 1e-6 else np.array([1.0, 0, 0])
        b = np.cross(d, a)
        psi = rng.uniform(0, 2 * math.pi)
        z6 = math.cos(psi) * a + math.sin(psi) * b
        R = np.column_stack([d, np.cross(z6, d), z6])
        if any(np.degrees(np.arccos(np.clip((np.trace(R.T @ R2) - 1) / 2, -1, 1))) < 25 for R2 in Rs):
            continue
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = target - R @ tool_nom
        if T[2, 3] < h_dev + 120:  # flange above the device
            continue
        seeds = [np.array([q1c + rng.normal(0, 20), rng.uniform(10, 60), rng.uniform(30, 110),
                           rng.uniform(-150, 150), s5 * rng.uniform(20, 90), rng.uniform(-150, 150)])
                 for s5 in (1, -1, 1, -1)]
        q = ik_nominal(robot, T, rng, seeds, q1c)
        if q is None or abs(q[4]) < 12:
            continue
        # wrist centre away from the device and the arm not folded on itself
        got.append(q)
        Rs.append(R)
    return got


def random_validation_configs(robot, rng, n):
    lim = robot["limits_deg"]
    out = []
    while len(out) < n:
        q = np.array([rng.uniform(-150, 150), rng.uniform(-50, 80), rng.uniform(0, 135), rng.uniform(-180, 180),
                      rng.uniform(-110, 110), rng.uniform(-180, 180)])
        if np.any(q < lim[:, 0]) or np.any(q > lim[:, 1]) or abs(q[4]) < 10:
            continue
        F = chain(robot, np.radians(q[None]) + np.radians(robot["offset_deg"]))[0]
        wc = F[4, :3, 3]
        tip = F[6, :3, :3] @ [0, 0, 150] + F[6, :3, 3]
        if tip[2] < -150 or wc[2] < -50 or np.hypot(wc[0], wc[1]) < 250:
            continue
        out.append(q)
    return np.array(out)


# ----------------------------------------------------------------------------------------------- one case
def simulate_case(cfg, outdir):
    seed = cfg["seed"] + int(os.environ.get("CAMPAIGN_SEED_OFFSET", "0"))   # rodlab: a held-out draw of every case
    rng = np.random.default_rng(seed)
    rng_noise = np.random.default_rng(seed + 100000)
    n_pos, n_or = cfg.get("n_pos", 5), cfg.get("n_orient", 6)
    effects = cfg.get("effects", [])
    eff = {e["type"]: e for e in effects}
    rod = json.load(open(ROD_FILE))
    nominal = load_robot_nominal()

    # lab
    T_BD = make_lab(rng, n_pos)
    T_WB = np.linalg.inv(T_BD[3])
    T_WD = {j: T_WB @ T_BD[j] for j in T_BD}
    T_WD[3] = np.eye(4)
    h_dev = T_BD[3][2, 3]

    # robot, rod
    robot, err_scale = draw_robot(rng)
    dth6_robot = robot["dtheta_deg"][5]
    tool_nom = np.array(rod["tool_mm"], float)
    tool_true = tool_nom + np.array([rng.normal(0, 0.6), 0.0, rng.normal(0, 0.6)])
    twist = rng.normal(0, 0.4)
    robot_c = copy_robot(robot)
    robot_c["dtheta_deg"][5] = dth6_robot + twist  # {T} turns with the rod (contract)
    k_rod = eff["rod_deflection"]["k"] if "rod_deflection" in eff else 1.0
    C_F = k_rod * np.array(rod["C_F_mm_per_N"])
    C_g = k_rod * np.array(rod["C_g_mm_per_g0"])
    if "rod_deflection" in eff and eff["rod_deflection"].get("file_zero"):
        C_F, C_g = np.array(rod["C_F_mm_per_N"]), np.array(rod["C_g_mm_per_g0"])
    phys = Physics(robot_c, T_WB, tool_true, rod, C_F, C_g, T_WD, effects)

    # time, temperature
    T0 = round(rng.uniform(19.0, 24.0), 2)
    ramp = cfg.get("temp_ramp_K", rng.uniform(-2.0, 2.0))
    # plan
    plan = []  # (pos, point, q_nominal)
    order = [j for j in range(1, n_pos + 1)]
    for j in order:
        qs = plan_orientations(nominal, T_BD[j], n_or, rng, tool_nom, h_dev)
        if len(qs) < n_or:
            raise RuntimeError(f"{cfg['name']}: only {len(qs)} orientations at position {j}")
        for i, q in enumerate(qs):
            plan.append((j, i + 1, q))
    N = len(plan)
    t = np.zeros(N)
    for n in range(1, N):
        same = plan[n][0] == plan[n - 1][0]
        t[n] = t[n - 1] + (rng.uniform(60, 150) if same else rng.uniform(250, 500))
    t = np.round(t)
    if "thermal" in eff and eff["thermal"]["driver"] == "temp":
        th = eff["thermal"]
        # room temperature: HVAC cycle + a step; not monotonic in time
        temp = T0 + th["temp_amp_K"] * np.sin(2 * np.pi * t / th["temp_period_s"] + th.get("temp_phase", 0.0)) \
            + th.get("temp_ramp_K", 0.0) * t / t[-1]
        temp = temp - temp[0] + T0
    else:
        temp = T0 + ramp * t / t[-1] + 0.1 * np.sin(2 * np.pi * t / rng.uniform(900, 2000))
    temp = np.round(temp + rng.normal(0, 0.01, N), 2)

    # approach directions (sign of each joint's last move), from the nominal plan
    qn = np.array([p[2] for p in plan])
    approach = np.zeros((N, 6))
    approach[0] = rng.choice([-1, 1], 6)
    for n in range(1, N):
        dq = qn[n] - qn[n - 1]
        approach[n] = np.where(np.abs(dq) > 1e-6, np.sign(dq), approach[n - 1])

    # align the ball on each datum (+ small residual offset, as the alignment loop leaves it), true model
    align = cfg.get("align_sigma_mm", 0.07)
    q_rep = np.zeros((N, 6))
    pos = [p[0] for p in plan]
    for n, (j, i, q0) in enumerate(plan):
        target = T_WD[j][:3, :3] @ rng.normal(0, align, 3) + T_WD[j][:3, 3]
        q = ik_refine(phys, q0, target, j, approach[n], t[n], temp[n], T0)
        q_rep[n] = np.round(q, 4)
    pW, RWT = phys.ball(q_rep, pos, approach, t, temp, T0)
    x_clean = phys.reading(pW, RWT, pos, rng_noise, noise=False)
    x = x_clean + rng_noise.normal(0, NOISE_DEVICE_MM, x_clean.shape)
    # outliers
    out_labels = []
    if "outliers" in eff:
        for (j, i, v) in eff["outliers"]["points"]:
            n = [k for k, p in enumerate(plan) if p[0] == j and p[1] == i][0]
            x[n] += v
            x_clean[n] += v
            out_labels.append(f"{j}.{i}")

    # recorded fixture poses: truth + measuring-arm error; fixture_pose effect adds a wrong offset / rotation
    rec, rec_clean = {}, {}
    for j in range(1, n_pos + 1):
        T = T_WD[j].copy()
        Tc = T.copy()
        if j != 3:
            dT = np.eye(4)
            dT[:3, :3] = rotvec(np.radians(rng_noise.normal(0, FIX_ERR_DEG, 3)))
            dT[:3, 3] = rng_noise.normal(0, FIX_ERR_MM, 3)
            T = T @ dT
        for e in [e for e in effects if e["type"] == "fixture_pose" and e["position"] == j]:
            for TT in (T, Tc):
                TT[:3, 3] += np.asarray(e["offset_mm"])
                if "rot_deg" in e:
                    TT[:3, :3] = rotvec(np.radians(e["rot_deg"])) @ TT[:3, :3]
        rec[j] = T
        rec_clean[j] = Tc

    # validation: 100 random configurations before the campaign, short rigid rod, tracker/scanner in {W}
    val_tool_nom = np.array([0.0, 0.0, 150.0])
    val_tool_true = val_tool_nom + rng.normal(0, 0.1, 3)
    robot_v = copy_robot(robot)  # no rod twist
    phys_v = Physics(robot_v, T_WB, val_tool_true, rod, np.zeros((3, 3)), np.zeros((3, 3)), T_WD,
                     [e for e in effects if e["type"] in ("periodic", "harmonic2", "backlash", "nonlinear_compliance",
                                                         "link_bending", "base_compliance", "mass_model")])
    qv = np.round(random_validation_configs(nominal, rng, 100), 4)
    apv = np.vstack([rng.choice([-1, 1], 6), np.sign(np.diff(qv, axis=0))])
    pv, _ = phys_v.ball(qv, [3] * len(qv), apv, tool=val_tool_true, rod_mass=0.3, rod_com_T=[0, 0, -60],
                        contact=False, deflect=False)
    pv = pv + rng_noise.normal(0, NOISE_VAL_MM, pv.shape)

    # ---------------- write
    os.makedirs(outdir, exist_ok=True)
    with_time = cfg.get("time_columns", True)
    with open(f"{outdir}/multical.campaign.csv", "w") as f:
        cols = "position,point,q1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm" + (",time_s,temp_C" if with_time else "")
        f.write(cols + "\n")
        for n, (j, i, _) in enumerate(plan):
            row = [str(j), str(i)] + [f"{v:.4f}" for v in q_rep[n]] + [f"{v:.4f}" for v in x[n]]
            if with_time:
                row += [f"{int(t[n])}", f"{temp[n]:.2f}"]
            f.write(",".join(row) + "\n")
    fix = {"format": "rodlab.fixture/1", "world_position": 3,
           "positions": {str(j): [round(v, 5) for v in (T_pose(rec[j]) if j != 3 else [0.0] * 6)]
                         for j in range(1, n_pos + 1)},
           "contact_force_N": F_D.tolist()}
    json.dump(fix, open(f"{outdir}/multical.fixture.json", "w"), indent=1)
    rod_out = dict(rod)
    if "rod_deflection" in eff and eff["rod_deflection"].get("file_zero"):
        rod_out = dict(rod, method="none", C_F_mm_per_N=[[0.0] * 3] * 3, C_g_mm_per_g0=[[0.0] * 3] * 3,
                       r_rod=1.0, c_rod_um=0.0)
    json.dump(rod_out, open(f"{outdir}/rod1.compliance.json", "w"), indent=1)
    with open(f"{outdir}/multical.validation.csv", "w") as f:
        f.write("# tool_mm: 0, 0, 150\n# rod_mass_kg: 0.3\n# rod_com_T_mm: 0, 0, -60\n")
        f.write(f"# temp_C: {T0:.2f}\n")
        f.write("q1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm\n")
        for n in range(len(qv)):
            f.write(",".join([f"{v:.4f}" for v in qv[n]] + [f"{v:.3f}" for v in pv[n]]) + "\n")

    truth = {
        "format": "indep.truth.campaign/1", "name": cfg["name"], "seed": seed, "group": cfg["group"],
        "description": cfg.get("description", ""),
        "effects": effects,
        "expected": cfg["expected"],
        "layout": {"positions": n_pos, "orientations": n_or, "align_sigma_mm": align,
                   "time_columns": with_time},
        "noise": {"device_mm": NOISE_DEVICE_MM, "validation_mm": NOISE_VAL_MM, "q_resolution_deg": 1e-4,
                  "fixture_pose_mm_deg": [FIX_ERR_MM, FIX_ERR_DEG]},
        "true_robot": {k: np.asarray(robot_c[k]).round(9).tolist() for k in
                       ("dtheta_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg", "c_rad_per_Nm")},
        "true_robot_note": "contract representation: dtheta_deg[5] includes the rod twist; d6/a6 errors folded "
                           "into the tool; the validation rod sees dtheta6 without the twist",
        "dtheta6_robot_deg": float(dth6_robot), "rod_twist_deg": float(twist), "error_scale": float(err_scale),
        "true_tool_mm": tool_true.round(6).tolist(),
        "true_base_pose_W": [round(v, 9) for v in T_pose(T_WB)],
        "true_fixture_poses_W": {str(j): [round(v, 9) for v in T_pose(T_WD[j])] for j in T_WD},
        "rod_true_C_scale": k_rod,
        "validation": {"tool_nom_mm": val_tool_nom.tolist(), "tool_true_mm": val_tool_true.round(6).tolist(),
                       "rod_mass_kg": 0.3, "rod_com_T_mm": [0, 0, -60], "temp_C": T0},
        "T0_C": T0, "outlier_points": out_labels,
    }
    json.dump(truth, open(f"{outdir}/truth.json", "w"), indent=1)
    # for self-checks (not given to rodlab)
    np.savez(f"{outdir}/.internal.npz", q=q_rep, x_clean=x_clean, x=x, pos=np.array(pos), t=t, temp=temp,
             rec=np.array([rec[j] for j in range(1, n_pos + 1)]),
             rec_clean=np.array([rec_clean[j] for j in range(1, n_pos + 1)]),
             T_WB=T_WB, tool=tool_true, approach=approach)
    return truth


# ----------------------------------------------------------------------------------------------- cases
def _exp(verdict, effects=(), locations=(), accept=None):
    d = {"verdict": verdict, "effects": list(effects), "locations": list(locations)}
    if accept:
        d["also_acceptable"] = accept
    return d


OOV = _exp("unexplained", [], [], accept={"verdicts": ["unexplained", "consistent"]})


def build_cases():
    C = []
    s = 1000

    def add(name, group, effects, expected, **kw):
        nonlocal s
        s += 1
        C.append(dict(name=name, group=group, seed=kw.pop("seed", s), effects=effects, expected=expected, **kw))

    # A. nulls
    add("null_a", "A", [], _exp("consistent"))
    add("null_b", "A", [], _exp("consistent"), temp_ramp_K=-2.5)
    add("null_c_4x5", "A", [], _exp("consistent"), n_pos=4, n_orient=5)
    add("null_d_6x8", "A", [], _exp("consistent"), n_pos=6, n_orient=8)
    add("null_e_notime", "A", [], _exp("consistent"), time_columns=False)
    add("null_f_5x7_wide_align", "A", [], _exp("consistent"), n_orient=7, align_sigma_mm=0.2)
    # B. single vocabulary effects
    add("rod_k0", "B", [{"type": "rod_deflection", "k": 0.0}], _exp("explained", ["rod_deflection"], [None]))
    add("rod_k0.8", "B", [{"type": "rod_deflection", "k": 0.8}], _exp("explained", ["rod_deflection"], [None]))
    add("rod_k1.5", "B", [{"type": "rod_deflection", "k": 1.5}], _exp("explained", ["rod_deflection"], [None]))
    add("rod_k3_6x5", "B", [{"type": "rod_deflection", "k": 3.0}], _exp("explained", ["rod_deflection"], [None]),
        n_pos=6, n_orient=5)
    add("rod_filezero", "B", [{"type": "rod_deflection", "k": 1.0, "file_zero": True}],
        _exp("explained", ["rod_deflection"], [None], accept={"locations": ["uncompensated", None]}))
    add("fix_p1_0.05", "B", [{"type": "fixture_pose", "position": 1, "offset_mm": [0.03, -0.035, 0.02]}],
        _exp("explained", ["fixture_pose"], ["position:1"]))
    add("fix_p4_0.15", "B", [{"type": "fixture_pose", "position": 4, "offset_mm": [-0.1, 0.08, 0.08]}],
        _exp("explained", ["fixture_pose"], ["position:4"]))
    add("fix_p2_0.3rot", "B", [{"type": "fixture_pose", "position": 2, "offset_mm": [0.12, 0.2, -0.18],
                                 "rot_deg": [0.05, -0.08, 0.03]}],
        _exp("explained", ["fixture_pose"], ["position:2"]))
    add("fix_p4_0.5_4x7", "B", [{"type": "fixture_pose", "position": 4, "offset_mm": [0.3, -0.3, 0.25]}],
        _exp("explained", ["fixture_pose"], ["position:4"]), n_pos=4, n_orient=7)
    add("per_j1_0.01", "B", [{"type": "periodic", "joint": 1, "amp_deg": 0.01, "phase_deg": 40}],
        _exp("explained", ["periodic_joint_error"], ["joint:1"]))
    add("per_j4_0.006", "B", [{"type": "periodic", "joint": 4, "amp_deg": 0.006, "phase_deg": -70}],
        _exp("explained", ["periodic_joint_error"], ["joint:4"]))
    add("per_j6_0.02", "B", [{"type": "periodic", "joint": 6, "amp_deg": 0.02, "phase_deg": 150}],
        _exp("explained", ["periodic_joint_error"], ["joint:6"]))
    add("per_j5_0.004", "B", [{"type": "periodic", "joint": 5, "amp_deg": 0.004, "phase_deg": 10}],
        _exp("explained", ["periodic_joint_error"], ["joint:5"]))
    add("thermal_time_0.04", "B", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.04}],
        _exp("explained", ["thermal_drift"], ["time"]), temp_ramp_K=0.0)
    add("thermal_time_0.1", "B", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.1}],
        _exp("explained", ["thermal_drift"], ["time"]), temp_ramp_K=0.3)
    add("thermal_temp_60ppmK", "B", [{"type": "thermal", "driver": "temp", "growth_ppm_per_K": 60.0,
                                      "temp_amp_K": 1.5, "temp_period_s": 2600.0, "temp_phase": 0.3}],
        _exp("explained", ["thermal_drift"], ["temp"]))
    add("outliers_2x0.15", "B", [{"type": "outliers", "points": [(2, 3, [0.09, -0.1, 0.06]),
                                                                 (5, 1, [-0.08, 0.02, 0.12])]}],
        _exp("explained", ["outliers"], ["points:2.3,5.1"]))
    add("outliers_3x0.3", "B", [{"type": "outliers", "points": [(1, 2, [0.2, 0.15, -0.15]),
                                                                (3, 5, [-0.1, -0.25, 0.1]),
                                                                (4, 6, [0.05, 0.2, 0.22])]}],
        _exp("explained", ["outliers"], ["points:1.2,3.5,4.6"]))
    add("outliers_2x0.5_5x8", "B", [{"type": "outliers", "points": [(1, 7, [0.3, -0.3, 0.25]),
                                                                    (4, 2, [-0.4, 0.1, -0.3])]}],
        _exp("explained", ["outliers"], ["points:1.7,4.2"]), n_orient=8)
    # B'. near the detection limit
    add("near_fix_p2_0.025", "B", [{"type": "fixture_pose", "position": 2, "offset_mm": [0.015, -0.015, 0.012]}],
        _exp("explained", ["fixture_pose"], ["position:2"]), seed=2001)
    add("near_per_j6_0.003", "B", [{"type": "periodic", "joint": 6, "amp_deg": 0.003, "phase_deg": 200}],
        _exp("explained", ["periodic_joint_error"], ["joint:6"]), seed=2002)
    add("near_thermal_time_0.015", "B", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.015}],
        _exp("explained", ["thermal_drift"], ["time"]), temp_ramp_K=0.0, seed=2003)
    add("near_rod_k1.15", "B", [{"type": "rod_deflection", "k": 1.15}],
        _exp("explained", ["rod_deflection"], [None]), seed=2004)
    add("null_g", "A", [], _exp("consistent"), seed=2005)
    add("null_h_4x8", "A", [], _exp("consistent"), n_pos=4, n_orient=8, seed=2006)
    # C. outside the vocabulary
    add("oov_harm2_j4", "C", [{"type": "harmonic2", "joint": 4, "amp_deg": 0.01, "phase_deg": 30}], OOV)
    add("oov_harm2_j6", "C", [{"type": "harmonic2", "joint": 6, "amp_deg": 0.02, "phase_deg": -100}], OOV)
    add("oov_backlash_j4", "C", [{"type": "backlash", "joint": 4, "lost_motion_deg": 0.02}], OOV)
    add("oov_backlash_j6", "C", [{"type": "backlash", "joint": 6, "lost_motion_deg": 0.03}], OOV)
    add("oov_nonlin_c_j2", "C", [{"type": "nonlinear_compliance", "joints": [2], "tau_s_Nm": 150.0}], OOV)
    add("oov_nonlin_c_j23", "C", [{"type": "nonlinear_compliance", "joints": [2, 3], "tau_s_Nm": 80.0}], OOV)
    add("oov_forearm_bend", "C", [{"type": "link_bending", "EI_Nm2": 2.0e4}], OOV)
    add("oov_forearm_bend_soft", "C", [{"type": "link_bending", "EI_Nm2": 7.0e3}], OOV)
    add("oov_base_mount", "C", [{"type": "base_compliance", "c_x_rad_per_Nm": 3e-7, "c_y_rad_per_Nm": 0.5e-7}],
        OOV)
    add("oov_device_skew_0.5", "C", [{"type": "device_axes", "sensor2_x_deg": 0.5, "sensor3_x_deg": -0.4,
                                      "sensor3_y_deg": 0.3}],
        _exp("unexplained", [], [], accept={"verdicts": ["unexplained", "consistent"],
                                            "project_effects": ["device_axes"]}), align_sigma_mm=0.25)
    add("oov_device_skew_2", "C", [{"type": "device_axes", "sensor2_x_deg": 2.0, "sensor3_x_deg": -1.5,
                                    "sensor3_y_deg": 1.0}],
        _exp("unexplained", [], [], accept={"verdicts": ["unexplained", "consistent"],
                                            "project_effects": ["device_axes"]}), align_sigma_mm=0.3)
    add("oov_sensor_gain_2pct", "C", [{"type": "sensor_gain", "gain": [0.0, 0.02, -0.015]}], OOV,
        align_sigma_mm=0.25)
    add("oov_sensor_gain_z3pct", "C", [{"type": "sensor_gain", "gain": [0.0, 0.0, 0.03]}], OOV,
        align_sigma_mm=0.3)
    add("oov_ball_ellipsoid_10um", "C", [{"type": "ball_shape", "semi_axis_err_mm": [0.010, -0.006, 0.0]}], OOV)
    add("oov_ball_ellipsoid_25um", "C", [{"type": "ball_shape", "semi_axis_err_mm": [0.025, 0.0, -0.02]}], OOV)
    add("oov_mass_model", "C", [{"type": "mass_model", "mass_scale": [1, 1.3, 0.8, 1.25, 1.2, 1],
                                 "com_shift_mm": [[0, 0, 0], [40, 0, 10], [0, 20, 30], [0, -40, 0], [0, 0, 0],
                                                  [0, 0, 0]]}], OOV)
    # C'. more seeds of the kinds that drew wrong causes in the first pass (added after it; seeds never used)
    add("oov_backlash_j5_s2", "C", [{"type": "backlash", "joint": 5, "lost_motion_deg": 0.02}], OOV, seed=4001)
    add("oov_backlash_j4_0.01_s3", "C", [{"type": "backlash", "joint": 4, "lost_motion_deg": 0.01}], OOV, seed=4002)
    add("oov_nonlin_c_j2_s2", "C", [{"type": "nonlinear_compliance", "joints": [2], "tau_s_Nm": 200.0}], OOV,
        seed=4003)
    add("oov_nonlin_c_j3", "C", [{"type": "nonlinear_compliance", "joints": [3], "tau_s_Nm": 40.0}], OOV, seed=4004)
    add("oov_harm2_j1", "C", [{"type": "harmonic2", "joint": 1, "amp_deg": 0.01, "phase_deg": 70}], OOV, seed=4005)
    add("oov_forearm_bend_medium", "C", [{"type": "link_bending", "EI_Nm2": 1.2e4}], OOV, seed=4006)
    add("thermal_temp_40ppmK_s2", "B", [{"type": "thermal", "driver": "temp", "growth_ppm_per_K": 40.0,
                                         "temp_amp_K": 1.2, "temp_period_s": 3100.0, "temp_phase": 1.0,
                                         "temp_ramp_K": 0.8}],
        _exp("explained", ["thermal_drift"], ["temp"]), seed=4007)
    # D. pairs
    add("pair_fix3_outl", "D", [{"type": "fixture_pose", "position": 5, "offset_mm": [0.15, -0.12, 0.1]},
                                {"type": "outliers", "points": [(2, 4, [0.25, -0.2, 0.1]), (4, 1, [-0.15, 0.3, 0.2])]}],
        _exp("explained", ["fixture_pose", "outliers"], ["position:5", "points:2.4,4.1"]))
    add("pair_per4_rod", "D", [{"type": "periodic", "joint": 4, "amp_deg": 0.012, "phase_deg": 80},
                               {"type": "rod_deflection", "k": 1.6}],
        _exp("explained", ["periodic_joint_error", "rod_deflection"], ["joint:4", None]))
    add("pair_thermal_fix", "D", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.08},
                                  {"type": "fixture_pose", "position": 2, "offset_mm": [-0.12, 0.1, -0.15]}],
        _exp("explained", ["thermal_drift", "fixture_pose"], ["time", "position:2"]), temp_ramp_K=0.2)
    return C


def build_probes():
    """diagnostic probes (scored separately): where does a finding come from?"""
    P = []

    def add(name, effects, expected, seed, **kw):
        P.append(dict(name=name, group="P", seed=seed, effects=effects, expected=expected, **kw))
    rod = lambda k: _exp("explained", ["rod_deflection"], [None])
    add("probe_rod_k0_s2", [{"type": "rod_deflection", "k": 0.0}], rod(0), 3001)
    add("probe_rod_k0_s3", [{"type": "rod_deflection", "k": 0.0}], rod(0), 3002)
    add("probe_rod_k0.2", [{"type": "rod_deflection", "k": 0.2}], rod(0), 3003)
    add("probe_rod_k0.4", [{"type": "rod_deflection", "k": 0.4}], rod(0), 3004)
    th = lambda: _exp("explained", ["thermal_drift"], ["time"])
    # same seed (same robot, lab, plan) as thermal_time_0.04 (seed 1020): only the scope of the growth differs
    for scope in ("all", "long", "links"):
        add(f"probe_thermal_0.04_{scope}", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.04,
                                             "scope": scope}], th(), 1020, temp_ramp_K=0.0)
    for scope in ("all", "long"):
        add(f"probe_thermal_0.1_{scope}", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.1,
                                            "scope": scope}], th(), 1021, temp_ramp_K=0.3)
    add("probe_pair_thermal_all_fix", [{"type": "thermal", "driver": "time", "growth_ppm_per_s": 0.08, "scope": "all"},
                                       {"type": "fixture_pose", "position": 2, "offset_mm": [-0.12, 0.1, -0.15]}],
        _exp("explained", ["thermal_drift", "fixture_pose"], ["time", "position:2"]), 1050, temp_ramp_K=0.2)
    # the rod part of pair_per4_rod alone, and the periodic part alone (same seed)
    add("probe_pair_per4_rod_rodonly", [{"type": "rod_deflection", "k": 1.6}], rod(1.6), 1049)
    add("probe_pair_per4_rod_peronly", [{"type": "periodic", "joint": 4, "amp_deg": 0.012, "phase_deg": 80}],
        _exp("explained", ["periodic_joint_error"], ["joint:4"]), 1049)
    return P


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else "/tmp/indep_campaign"
    only = sys.argv[2:] if len(sys.argv) > 2 else None
    cases = build_cases() + build_probes()
    for cfg in cases:
        if only and cfg["name"] not in only:
            continue
        d = f"{out}/cases/{cfg['name']}"
        if os.path.isdir(d):
            shutil.rmtree(d)
        simulate_case(cfg, d)
        print("wrote", d, flush=True)
    json.dump([{k: v for k, v in c.items()} for c in cases], open(f"{out}/cases.json", "w"), indent=1,
              default=str)


if __name__ == "__main__":
    main()
