"""Self-checks of the simulator with an independent identification (my own, not rodlab's):
  1. true model: the readings against the TRUE model (true robot, rod, base, recorded fixture poses) -> noise level
     for nulls;
  2. the contract's model (32 parameters as in the examples' oracle: dth2-6, d3-5, a1-5, al1-5, be2, c2-6, base,
     tool x/z) fitted to the noisy readings: residual rms and reduced chi-square;
  3. the same fit on the noise-free readings (recorded fixture poses without the measuring-arm error): what of the
     effect the model cannot absorb = the detectable signal (rms, max, delta chi^2 = sum r^2 / sigma^2).
usage: python check.py CASE_DIR [...]   -> prints and writes CASE_DIR/selfcheck.json
"""
import json
import os
import sys

import numpy as np
from scipy.optimize import least_squares

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from model import G0, copy_robot, flange, load_robot_nominal, pose_T
from sim import F_D, NOISE_DEVICE_MM

NAMES = ([f"dth{i}" for i in range(2, 7)] + ["d3", "d4", "d5"] + [f"a{i}" for i in range(1, 6)]
         + [f"al{i}" for i in range(1, 6)] + ["be2"] + [f"c{i}" for i in range(2, 7)]
         + ["bx", "by", "bz", "ba", "bb", "bc", "tx", "tz"])


def unpack(p, nominal):
    r = copy_robot(nominal)
    r["dtheta_deg"] = np.r_[0.0, p[0:5]]
    r["d_mm"] = nominal["d_mm"].copy()
    r["d_mm"][2:5] = p[5:8]
    r["a_mm"] = nominal["a_mm"].copy()
    r["a_mm"][0:5] = p[8:13]
    r["alpha_deg"] = nominal["alpha_deg"].copy()
    r["alpha_deg"][0:5] = p[13:18]
    r["beta_deg"] = np.array([0, p[18], 0, 0, 0, 0.0])
    r["c_rad_per_Nm"] = np.r_[0.0, p[19:24] * 1e-6]
    base = p[24:30]
    tool = np.array([p[30], 0.0, p[31]])
    return r, base, tool


def pack(truth):
    t = truth["true_robot"]
    return np.r_[t["dtheta_deg"][1:6], t["d_mm"][2:5], t["a_mm"][0:5], t["alpha_deg"][0:5], t["beta_deg"][1],
                 np.array(t["c_rad_per_Nm"][1:6]) * 1e6, truth["true_base_pose_W"],
                 truth["true_tool_mm"][0], truth["true_tool_mm"][2]]


def model_residual(p, nominal, rod, C_F, C_g, q, x, pos, Trec, robot=None):
    r, base, tool = unpack(p, nominal)
    if robot is not None:
        r = robot
    TB = pose_T(base)
    RB = TB[:3, :3]
    fW = np.array([Trec[j][:3, :3] @ F_D for j in pos])
    fB = fW @ RB
    F, _, _ = flange(r, q, tool, rod["mass_kg"], rod["com_T_mm"], force_base_fn=lambda F: fB, n_iter=4)
    R6 = F[:, 6, :3, :3]
    pB = np.einsum("nij,j->ni", R6, tool) + F[:, 6, :3, 3]
    gT = np.einsum("nji,j->ni", R6, r["gravity_base"] / G0)
    fT = np.einsum("nji,nj->ni", R6, fB)
    dT = gT @ C_g.T + fT @ C_F.T
    comp_W = np.einsum("ij,njk,nk->ni", RB, R6, dT)
    pW = pB @ RB.T + TB[:3, 3]
    meas_W = np.array([Trec[j][:3, :3] @ xx + Trec[j][:3, 3] for j, xx in zip(pos, x)]) - comp_W
    return (meas_W - pW).ravel()


def fit(p0, nominal, rod, C_F, C_g, q, x, pos, Trec, sigma=NOISE_DEVICE_MM):
    def f(p):
        res = model_residual(p, nominal, rod, C_F, C_g, q, x, pos, Trec) / sigma
        prior = p[19:24] / 10.0  # weak prior c ~ N(0, 1e-5 rad/(N m))
        return np.r_[res, prior]
    sol = least_squares(f, p0, method="trf", x_scale=np.r_[[0.05] * 5, [0.3] * 8, [0.03] * 6, [3.0] * 5,
                                                           [0.3] * 3, [0.03] * 3, [0.3] * 2],
                        xtol=1e-10, ftol=1e-12, max_nfev=200)
    r = model_residual(sol.x, nominal, rod, C_F, C_g, q, x, pos, Trec)
    return sol.x, r


def selfcheck(case):
    truth = json.load(open(f"{case}/truth.json"))
    z = np.load(f"{case}/.internal.npz")
    rod = json.load(open(f"{case}/rod1.compliance.json"))
    C_F, C_g = np.array(rod["C_F_mm_per_N"]), np.array(rod["C_g_mm_per_g0"])
    nominal = load_robot_nominal()
    q, x, xc, pos = z["q"], z["x"], z["x_clean"], [int(v) for v in z["pos"]]
    Trec = {j + 1: T for j, T in enumerate(z["rec"])}
    Trec_c = {j + 1: T for j, T in enumerate(z["rec_clean"])}
    p_true = pack(truth)
    n = x.size
    out = {}
    rt = copy_robot(nominal)
    for k in ("dtheta_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg", "c_rad_per_Nm"):
        rt[k] = np.array(truth["true_robot"][k])
    r0 = model_residual(p_true, nominal, rod, C_F, C_g, q, x, pos, Trec, robot=rt)
    out["true_model_rms_um"] = float(np.sqrt(np.mean(r0 ** 2)) * 1e3)
    r0c = model_residual(p_true, nominal, rod, C_F, C_g, q, xc, pos, Trec_c, robot=rt)
    out["true_model_clean_rms_um"] = float(np.sqrt(np.mean(r0c ** 2)) * 1e3)
    p, r = fit(p_true, nominal, rod, C_F, C_g, q, x, pos, Trec)
    out["fit_rms_um"] = float(np.sqrt(np.mean(r ** 2)) * 1e3)
    out["fit_reduced_chi2"] = float(np.sum((r / NOISE_DEVICE_MM) ** 2) / (n - 32))
    pc, rc = fit(p_true, nominal, rod, C_F, C_g, q, xc, pos, Trec_c)
    out["signal_rms_um"] = float(np.sqrt(np.mean(rc ** 2)) * 1e3)
    out["signal_max_um"] = float(np.abs(rc).max() * 1e3)
    out["signal_delta_chi2"] = float(np.sum((rc / NOISE_DEVICE_MM) ** 2))
    rr = rc.reshape(-1, 3)
    worst = np.argsort(-np.linalg.norm(rr, axis=1))[:3]
    labels = [f"{pos[k]}.{sum(1 for m in range(k + 1) if pos[m] == pos[k])}" for k in worst]
    out["signal_worst_points"] = labels
    out["detectable"] = ("yes" if out["signal_delta_chi2"] > 40 else
                         "marginal" if out["signal_delta_chi2"] > 15 else "no")
    json.dump(out, open(f"{case}/selfcheck.json", "w"), indent=1)
    return out


if __name__ == "__main__":
    for c in sys.argv[1:]:
        o = selfcheck(c)
        print(os.path.basename(c.rstrip("/")), json.dumps({k: (round(v, 2) if isinstance(v, float) else v)
                                                           for k, v in o.items()}), flush=True)
