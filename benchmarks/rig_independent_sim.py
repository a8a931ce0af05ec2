"""Independent stiffness-rig simulator for testing `rodlab diagnose --rig` (written 2026-11-27 by a helper that saw
only the contract, not rodlab's simulator; kept as it was written, its case list included; driven by
``benchmarks/rig_independent.py``).

numpy only.  The only thing taken from rodlab is the design's nominal C_F, read from a
compliance file written by `rodlab compliance <design> -o <design>.compliance.json`
(contract rodlab.compliance/1).  Everything else (load schedule, loading chain, gauges,
zeroing, noise, effects) is modelled here, independently of rodlab's stiffness_rig code.

Physics (my own forms):
  * load chain: a hanger of mass m on slides; the force reaching the ball is a vector
    f(t) = F(t) * u_series, u_series the (possibly tilted) load direction of the series.
    The load changes by a linear ramp during the gap between holds (no samples in the gap).
  * rod: u_ball = C_true @ (f + creep states); creep = sum of Kelvin-Voigt elements driven by f
    (integrated with an exponential integrator at dt = 5 ms, superposition over the history).
  * friction: per hold the slide's friction force F_f*(1 + 0.15 N(0,1)) holds back the
    hanger while masses are added (phase load) and pushes while they are removed (unload);
    clipped to the hanging weight; no hanger (mass 0) -> no force at all.
  * tare: an unrecorded dead mass on the hanger whenever the hanger is on (mass_kg > 0).
  * joint at the flange: a rotational spring S (bend, bend, torsion about pipe I = z_T) at the
    flange face; dC = [r]x^T S [r]x with r the vector flange -> ball.
  * gauges: gauge a reads g_a * (d_a + drift_a(t)) relative to its reading at zeroing time
    (one noisy reading, taken at the start of each series); white noise sigma; quantised to
    the resolution; optional gain error on one gauge.
  * drift: time ("warm-up" exponential + linear) or temperature-linked.
  * load cell (v1.1 force_N): measures the force the rod carries (after friction), with noise.
"""
import argparse
import json
import os
import numpy as np

G0 = 9.80665
AX = {'x': 0, 'y': 1, 'z': 2}
HERE = os.environ.get('RIG_INDEPENDENT_DIR', os.path.dirname(os.path.abspath(__file__)))


def axis_vec(a):
    s = -1.0 if a.startswith('-') else 1.0
    v = np.zeros(3)
    v[AX[a[-1]]] = s
    return v


def skew(r):
    return np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]], float)


def load_design(design):
    d = json.load(open(os.path.join(HERE, f'{design}.compliance.json')))
    return np.array(d['C_F_mm_per_N'], float), np.array(d['tool_mm'], float), d['rod']


# ---------------------------------------------------------------- protocols (my own)
def protocol(name):
    """Returns dict: series list of (axis, measured gauges, [(phase, mass, repeat), ...]),
    hold_s, rate_Hz, gap_s, remount_s, step0, repeat0."""
    if name == 'P1':   # z, x, y; 4 masses, 3 repeats, 10 s @ 5 Hz
        ax = [('z', 'zx'), ('x', 'xz'), ('y', 'yz')]
        masses = [0.4, 0.8, 1.2, 1.6]
        reps, hold, rate, gap, r0, s0 = 3, 10.0, 5.0, 3.0, 1, 1
        cyc = 'updown'
    elif name == 'P2':  # x, y, z; 6 masses, 2 repeats, 6 s @ 20 Hz
        ax = [('x', 'xz'), ('y', 'yx'), ('z', 'zx')]
        masses = [0.25, 0.5, 0.75, 1.0, 1.25, 1.5]
        reps, hold, rate, gap, r0, s0 = 2, 6.0, 20.0, 2.0, 0, 0
        cyc = 'updown'
    elif name == 'P3':  # y, z, x; 5 masses to 2.5 kg, 4 repeats, 15 s @ 4 Hz, 5 s gaps
        ax = [('y', 'yz'), ('z', 'zx'), ('x', 'xz')]
        masses = [0.5, 1.0, 1.5, 2.0, 2.5]
        reps, hold, rate, gap, r0, s0 = 4, 15.0, 4.0, 5.0, 1, 100
        cyc = 'updown'
    elif name == 'P4':  # minor loops within each repeat, z, y, x; 8 s @ 10 Hz
        ax = [('z', 'zx'), ('y', 'yz'), ('x', 'xz')]
        masses = None
        reps, hold, rate, gap, r0, s0 = 3, 8.0, 10.0, 4.0, 1, 1
        cyc = 'minor'
    elif name == 'P5':  # negative axes, 3 masses, 5 repeats, 5 s @ 10 Hz
        ax = [('-z', 'zx'), ('-x', 'xz'), ('y', 'yz')]
        masses = [0.5, 1.0, 1.5]
        reps, hold, rate, gap, r0, s0 = 5, 5.0, 10.0, 2.5, 1, 1
        cyc = 'updown'
    elif name == 'P6':  # long holds for creep: 30 s @ 2 Hz, 2 repeats, y z x
        ax = [('y', 'yz'), ('z', 'zx'), ('x', 'xz')]
        masses = [0.5, 1.0, 1.5, 2.0]
        reps, hold, rate, gap, r0, s0 = 2, 30.0, 2.0, 3.0, 1, 1
        cyc = 'updown'
    else:
        raise ValueError(name)
    series = []
    for a, gauges in ax:
        holds = [('load', 0.0, r0)]
        for k in range(reps):
            r = r0 + k
            if cyc == 'updown':
                seq = [('load', m) for m in masses] + [('unload', m) for m in masses[-2::-1]] + [('unload', 0.0)]
            else:
                seq = [('load', 0.5), ('load', 1.0), ('load', 1.5), ('unload', 1.0), ('load', 1.5),
                       ('load', 2.0), ('unload', 1.5), ('unload', 1.0), ('unload', 0.5), ('unload', 0.0)]
            holds += [(p, m, r) for p, m in seq]
        series.append((a, gauges, holds))
    return dict(series=series, hold_s=hold, rate_Hz=rate, gap_s=gap, remount_s=60.0, step0=s0, name=name)


# ---------------------------------------------------------------- simulator
def simulate(case, outdir):
    rng = np.random.default_rng(case['seed'])
    C_sim, tool, rodname = load_design(case['design'])
    eff = case.get('effects', {})
    C = C_sim.copy()
    if 'scale' in eff:
        C = C * eff['scale']['r']
    if 'joint' in eff:
        sb = eff['joint']['s_bend_rad_per_Nm'] / 1000.0     # rad/(N mm)
        st = eff['joint']['s_torsion_rad_per_Nm'] / 1000.0
        r = tool.copy()               # flange face at the {6} origin; {T} axes = {6} axes
        S = np.diag([sb, sb, st])     # bend about x,y of pipe I (along z), torsion about z
        K = skew(r)
        C = C + K.T @ S @ K
    P = protocol(case['protocol'])
    sigma = case['noise_um'] / 1000.0
    res = case.get('resolution_um', 1.0) / 1000.0
    rate = P['rate_Hz']
    hold, gap = P['hold_s'], P['gap_s']

    # build the timeline: (t_start, t_end, axis, gauges, phase, mass, repeat, step, series index)
    holds = []
    t = 0.0
    step = P['step0']
    for si, (a, gauges, hl) in enumerate(P['series']):
        if si > 0:
            t += P['remount_s']
        for hi, (ph, m, r) in enumerate(hl):
            if hi > 0:
                t += gap
            holds.append(dict(t0=t, t1=t + hold, axis=a, gauges=gauges, phase=ph, mass=m, rep=r,
                              step=step, si=si, first=(hi == 0)))
            t += hold
            step += 1
    T_end = t

    # load directions per series (misalignment)
    u_ser = []
    for si, (a, gauges, hl) in enumerate(P['series']):
        u = axis_vec(a)
        if 'tilt' in eff:
            e = np.deg2rad(eff['tilt']['deg'][si] if isinstance(eff['tilt']['deg'], list) else eff['tilt']['deg'])
            n = rng.normal(size=3)
            n -= n.dot(u) * u
            n /= np.linalg.norm(n)
            u = np.cos(e) * u + np.sin(e) * n
        u_ser.append(u)

    # force magnitude per hold (what the rod carries)
    Ff = eff.get('friction', {}).get('F_f_N', 0.0)
    tare = eff.get('tare', {}).get('tare_kg', 0.0)
    fscat = eff.get('friction', {}).get('scatter', 0.15)      # hold-to-hold scatter of the friction
    fzero = eff.get('friction', {}).get('stuck_at_zero', False)  # True: the slide stays stuck on the rod at
    for h in holds:                                              # an unload to mass 0 (rodlab's convention)
        W = (h['mass'] + (tare if h['mass'] > 0 else 0.0)) * G0
        if Ff > 0 and (h['mass'] > 0 or (fzero and h['phase'] == 'unload')):
            f = Ff * (1 + fscat * rng.normal())
            f = max(f, 0.0) if (fzero and h['mass'] == 0) else min(max(f, 0.0), W)
            W = W - f if h['phase'] == 'load' else W + f
        h['F'] = W

    # fine time grid; force vector piecewise constant in holds, linear ramps in gaps, 0 in remounts
    dt = 0.005
    tg = np.arange(0.0, T_end + dt, dt)
    Fv = np.zeros((tg.size, 3))
    for i, h in enumerate(holds):
        sel = (tg >= h['t0']) & (tg <= h['t1'])
        Fv[sel] = h['F'] * u_ser[h['si']]
        if not h['first']:
            prev = holds[i - 1]
            sg = (tg > prev['t1']) & (tg < h['t0'])
            w = (tg[sg] - prev['t1']) / (h['t0'] - prev['t1'])
            Fv[sg] = ((1 - w)[:, None] * prev['F'] * u_ser[prev['si']] + w[:, None] * h['F'] * u_ser[h['si']])
    # creep: Kelvin-Voigt states x_k' = (phi_k f - x_k) / tau_k
    Feff = Fv.copy()
    if 'creep' in eff:
        for phi, tau in zip(eff['creep']['phi'], eff['creep']['tau_s']):
            a_ = np.exp(-dt / tau)
            x = np.zeros(3)
            X = np.zeros_like(Fv)
            for k in range(tg.size):
                x = a_ * x + (1 - a_) * phi * Fv[k]
                X[k] = x
            Feff += X
    D = Feff @ C.T      # true ball displacement (mm), {T}

    # temperature
    T0 = 20.5 + rng.uniform(0, 1.5)
    Tamp = rng.uniform(0.3, 1.2)
    Tper = rng.uniform(1500, 4000)
    Tph = rng.uniform(0, 2 * np.pi)
    temp = lambda tt: T0 + Tamp * np.sin(2 * np.pi * tt / Tper + Tph)

    # gauge zero drift (mm) as function of time and temperature
    def drift(tt):
        out = np.zeros((np.size(tt), 3))
        if 'drift_time' in eff:
            d = eff['drift_time']
            for a, rt in d['rate_mm_per_s'].items():    # warm-up exponential + linear
                out[:, AX[a]] += rt * tt + d.get('warm_mm', 0.0) * (1 - np.exp(-tt / d.get('warm_tau_s', 600.0)))
        if 'drift_temp' in eff:
            for a, k in eff['drift_temp']['mm_per_K'].items():
                out[:, AX[a]] += k * (temp(tt) - T0)
        return out

    gain = np.ones(3)
    if 'gain' in eff:
        gain[AX[eff['gain']['gauge']]] = 1 + eff['gain']['error']

    rows = []
    lc_sigma = case.get('load_cell_N')
    for si, (a, gauges, hl) in enumerate(P['series']):
        hs = [h for h in holds if h['si'] == si]
        t_zero = hs[0]['t0']    # zeroed on one reading at the start of the series
        k0 = int(round(t_zero / dt))
        zero = gain * (D[k0] + drift(np.array([t_zero]))[0]) + sigma * rng.normal(size=3)
        for h in hs:
            n = int(round(hold * rate))
            ts = h['t0'] + np.arange(n) / rate
            kk = np.clip(np.round(ts / dt).astype(int), 0, tg.size - 1)
            raw = gain * (D[kk] + drift(ts)) + sigma * rng.normal(size=(n, 3))
            rd = raw - zero
            rd = np.round(rd / res) * res
            for j in range(n):
                cells = []
                for ax_ in 'xyz':
                    cells.append(f'{rd[j, AX[ax_]]:.4f}' if ax_ in gauges else '')
                row = [f'{ts[j]:.3f}', str(h['step']), str(h['rep']), h['phase'], a, f'{h["mass"]:.4f}'] + cells
                row.append(f'{temp(ts[j]) + 0.01 * rng.normal():.2f}')
                if lc_sigma is not None:
                    fval = h['F'] + lc_sigma * rng.normal() if h['mass'] > 0 else lc_sigma * rng.normal()
                    row.append(f'{fval:.4f}')
                rows.append(','.join(row))
    name = case['name']
    path = os.path.join(outdir, f'{name}.rig.csv')
    with open(path, 'w') as fh:
        fh.write('# format: rodlab.rig/1\n')
        fh.write(f'# rod: {rodname}\n')
        fh.write(f'# sample_rate_Hz: {rate:g}\n')
        fh.write(f'# resolution_mm: {res:g}\n')
        fh.write('# generator: benchmarks/rig_independent_sim.py (independent)\n')
        hdr = 'time_s,step,repeat,phase,load_axis,mass_kg,disp_x_mm,disp_y_mm,disp_z_mm,temp_C'
        if lc_sigma is not None:
            fh.write('# load_N: force_N (load cell)\n')
            hdr += ',force_N'
        else:
            fh.write('# load_N: mass_kg * 9.80665\n')
        fh.write(hdr + '\n')
        fh.write('\n'.join(rows) + '\n')
    truth = dict(case)
    truth['C_F_sim_mm_per_N'] = C_sim.tolist()
    truth['C_F_true_mm_per_N'] = C.tolist()
    truth['load_dirs'] = [u.tolist() for u in u_ser]
    truth['n_rows'] = len(rows)
    truth['duration_s'] = T_end
    # peak change of the readings caused by the effects vs a clean twin: left to the report
    json.dump(truth, open(os.path.join(outdir, f'{name}.truth.json'), 'w'), indent=1)
    return path


# ---------------------------------------------------------------- the case list
def cases():
    L = []

    def add(name, design, proto, seed, effects, expect, noise=1.0, res=1.0, **kw):
        d = dict(name=name, design=design, protocol=proto, seed=seed, effects=effects,
                 expected=expect, noise_um=noise, resolution_um=res)
        d.update(kw)
        L.append(d)

    # (a) clean
    add('a1_clean_rod1_P1', 'rod1', 'P1', 11, {}, ['consistent'], noise=0.8)
    add('a2_clean_rod1_P2', 'rod1', 'P2', 12, {}, ['consistent'], noise=1.5, res=0.5)
    add('a3_clean_rod1_P5neg', 'rod1', 'P5', 13, {}, ['consistent'], noise=0.6)
    add('a4_clean_rod4_P3', 'rod4', 'P3', 14, {}, ['consistent'], noise=2.0)
    add('a5_clean_rod1_P4minor', 'rod1', 'P4', 15, {}, ['consistent'], noise=1.0)
    # (b) compliance scale
    add('b1_softer30_rod1_P1', 'rod1', 'P1', 21, {'scale': {'r': 1.30}}, ['compliance_scale|model_form'])
    add('b2_stiffer25_rod1_P2', 'rod1', 'P2', 22, {'scale': {'r': 0.75}}, ['compliance_scale|model_form'])
    add('b3_softer40_rod4_P4', 'rod4', 'P4', 23, {'scale': {'r': 1.40}}, ['compliance_scale'], noise=1.5)
    add('b4_stiffer20_rod4_P5', 'rod4', 'P5', 24, {'scale': {'r': 0.80}}, ['compliance_scale'], noise=1.0)
    add('b5_softer25_rod4_P1', 'rod4', 'P1', 25, {'scale': {'r': 1.25}}, ['compliance_scale'], noise=1.0)
    add('b6_softer35_rod4_P3', 'rod4', 'P3', 26, {'scale': {'r': 1.35}}, ['compliance_scale'], noise=1.5)
    # (c) friction
    add('c1_friction03_rod1_P1', 'rod1', 'P1', 31, {'friction': {'F_f_N': 0.3}}, ['friction'])
    add('c2_friction05_rod1_P3', 'rod1', 'P3', 32, {'friction': {'F_f_N': 0.5}}, ['friction'], noise=1.5)
    add('c3_friction02_rod4_P2', 'rod4', 'P2', 33, {'friction': {'F_f_N': 0.2}}, ['friction'], noise=1.0)
    add('c4_friction04_rod1_P4minor', 'rod1', 'P4', 34, {'friction': {'F_f_N': 0.4}}, ['friction'])
    # (d) creep
    add('d1_creep3pc_tau8_rod1_P6', 'rod1', 'P6', 41, {'creep': {'phi': [0.03], 'tau_s': [8.0]}}, ['creep'])
    add('d2_creep2exp_rod1_P3', 'rod1', 'P3', 42, {'creep': {'phi': [0.015, 0.02], 'tau_s': [3.0, 40.0]}}, ['creep'])
    add('d3_creep2pc_tau15_rod4_P1', 'rod4', 'P1', 43, {'creep': {'phi': [0.02], 'tau_s': [15.0]}}, ['creep'], noise=1.5)
    add('d4_creep4pc_tau5_rod1_P2', 'rod1', 'P2', 44, {'creep': {'phi': [0.04], 'tau_s': [5.0]}}, ['creep'])
    # (e) gauge gain error (outside the vocabulary): honest answer unexplained (sensor) or, where it is
    # indistinguishable from a compliance entry, model_form / consistent
    add('e1_gain_z+6pc_rod1_P1', 'rod1', 'P1', 51, {'gain': {'gauge': 'z', 'error': 0.06}}, ['unexplained|model_form'])
    add('e2_gain_x-5pc_rod1_P3', 'rod1', 'P3', 52, {'gain': {'gauge': 'x', 'error': -0.05}}, ['unexplained|model_form'])
    add('e3_gain_z+4pc_rod4_P2', 'rod4', 'P2', 53, {'gain': {'gauge': 'z', 'error': 0.04}}, ['unexplained|model_form'])
    add('e4_gain_y+8pc_rod4_P1', 'rod4', 'P1', 54, {'gain': {'gauge': 'y', 'error': 0.08}}, ['unexplained|model_form|torsion_compliance'])
    # (f) load misalignment 1-3 deg
    add('f1_tilt2deg_rod1_P1', 'rod1', 'P1', 61, {'tilt': {'deg': 2.0}}, ['crosstalk'])
    add('f2_tilt3deg_rod1_P2', 'rod1', 'P2', 62, {'tilt': {'deg': [3.0, 1.5, 2.5]}}, ['crosstalk'])
    add('f3_tilt1.5deg_rod4_P3', 'rod4', 'P3', 63, {'tilt': {'deg': 1.5}}, ['crosstalk'], noise=1.5)
    # (g) compliant joint at the flange
    add('g1_joint_flange_5e-6_rod1_P1', 'rod1', 'P1', 71, {'joint': {'s_bend_rad_per_Nm': 5e-6, 's_torsion_rad_per_Nm': 2e-6}}, ['joint_compliance@flange_clamp|model_form'])
    add('g2_joint_flange_1.5e-5_rod1_P3', 'rod1', 'P3', 72, {'joint': {'s_bend_rad_per_Nm': 1.5e-5, 's_torsion_rad_per_Nm': 5e-6}}, ['joint_compliance@flange_clamp'])
    add('g3_joint_flange_4e-5_rod4_P2', 'rod4', 'P2', 73, {'joint': {'s_bend_rad_per_Nm': 4e-5, 's_torsion_rad_per_Nm': 1e-5}}, ['joint_compliance@flange_clamp'])
    # (h) tare / offset drift
    add('h1_tare0.12_rod1_P1', 'rod1', 'P1', 81, {'tare': {'tare_kg': 0.12}}, ['tare'])
    add('h2_tare0.08_rod4_P5', 'rod4', 'P5', 82, {'tare': {'tare_kg': 0.08}}, ['tare'], noise=1.5)
    add('h3_drift_time_rod1_P3', 'rod1', 'P3', 83, {'drift_time': {'rate_mm_per_s': {'y': 2.0e-5, 'z': -1.5e-5, 'x': 1.0e-5}, 'warm_mm': 0.004, 'warm_tau_s': 500.0}}, ['drift'])
    add('h4_drift_temp_rod1_P1', 'rod1', 'P1', 84, {'drift_temp': {'mm_per_K': {'y': 0.006, 'z': 0.005, 'x': -0.004}}}, ['drift'])
    # (i) combinations of two
    add('i1_friction+creep_rod1_P3', 'rod1', 'P3', 91, {'friction': {'F_f_N': 0.4}, 'creep': {'phi': [0.03], 'tau_s': [10.0]}}, ['friction', 'creep'])
    add('i2_scale0.7+drift_rod4_P1', 'rod4', 'P1', 92, {'scale': {'r': 0.7}, 'drift_time': {'rate_mm_per_s': {'y': 1.5e-5, 'z': 1.5e-5, 'x': 1.5e-5}}}, ['compliance_scale', 'drift'], noise=1.5)
    add('i3_joint+friction_rod1_P2', 'rod1', 'P2', 93, {'joint': {'s_bend_rad_per_Nm': 1.5e-5, 's_torsion_rad_per_Nm': 5e-6}, 'friction': {'F_f_N': 0.3}}, ['joint_compliance@flange_clamp', 'friction'])
    add('i4_tilt+tare_rod1_P1', 'rod1', 'P1', 94, {'tilt': {'deg': 2.0}, 'tare': {'tare_kg': 0.1}}, ['crosstalk', 'tare'])
    add('i5_gain+creep_rod1_P6', 'rod1', 'P6', 95, {'gain': {'gauge': 'z', 'error': 0.06}, 'creep': {'phi': [0.03], 'tau_s': [8.0]}}, ['creep', 'unexplained|model_form'])
    # friction variants (to find what the spurious tare comes from)
    add('k1_friction05_noscatter_rod1_P3', 'rod1', 'P3', 32, {'friction': {'F_f_N': 0.5, 'scatter': 0.0}}, ['friction'], noise=1.5)
    add('k2_friction05_stuckzero_rod1_P3', 'rod1', 'P3', 32, {'friction': {'F_f_N': 0.5, 'scatter': 0.0, 'stuck_at_zero': True}}, ['friction'], noise=1.5)
    add('k3_friction02_noscatter_rod4_P2', 'rod4', 'P2', 33, {'friction': {'F_f_N': 0.2, 'scatter': 0.0}}, ['friction'], noise=1.0)
    add('k4_friction02_stuckzero_rod4_P2', 'rod4', 'P2', 33, {'friction': {'F_f_N': 0.2, 'scatter': 0.0, 'stuck_at_zero': True}}, ['friction'], noise=1.0)
    add('k5_friction03_stuckzero_scatter_rod1_P1', 'rod1', 'P1', 31, {'friction': {'F_f_N': 0.3, 'stuck_at_zero': True}}, ['friction'])
    # v1.1 load cell: friction present but measured -> no friction expected
    add('j1_friction_loadcell_rod1_P1', 'rod1', 'P1', 101, {'friction': {'F_f_N': 0.4}}, ['consistent'], load_cell_N=0.005)
    add('j2_clean_loadcell_rod4_P2', 'rod4', 'P2', 102, {}, ['consistent'], load_cell_N=0.01)
    return L


if __name__ == '__main__':
    ap = argparse.ArgumentParser()
    ap.add_argument('--out', default=os.path.join(HERE, 'recs'))
    ap.add_argument('--only', default=None, help='comma list of case names')
    ap.add_argument('--seed-offset', type=int, default=0, help='added to every case seed (a held-out draw; rodlab)')
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    only = set(a.only.split(',')) if a.only else None
    for c in cases():
        if only and c['name'] not in only:
            continue
        c['seed'] += a.seed_offset
        p = simulate(c, a.out)
        print(p)
