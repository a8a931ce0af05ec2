"""Hypothesis library of the rig diagnosis: each effect of ``contract/effects.md`` (subject ``rig``) as
columns (linear in its parameters) added to the simulated model of every sample.

The simulated model of a sample is ``d_c = C_sim[c, a] F`` (F the load along axis a, signed). Every term
returns a design matrix (n_samples x k) whose columns multiply the term's parameters, with physical bounds.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rodlab.units import G0

__all__ = ["RigData", "Term", "rig_terms", "creep_term", "CREEP_TAU_GRID_S", "spring_columns", "spring_matrices"]


@dataclass
class RigData:
    """Samples flattened over measured components: y [mm], component c, load axis index a, sign, force F [N],
    mass [kg], phase (0 load / 1 unload), series-start reference flag, time since the hold start and since the
    series start [s], temperature, step, repeat, hold id."""

    y: np.ndarray
    comp: np.ndarray
    axis: np.ndarray
    sign: np.ndarray
    F: np.ndarray
    mass: np.ndarray
    unload: np.ndarray
    reference: np.ndarray
    t_hold: np.ndarray
    t_series: np.ndarray
    temp: np.ndarray
    step: np.ndarray
    repeat: np.ndarray
    t_abs: np.ndarray


@dataclass
class Term:
    """A hypothesis: effect ID, location key, parameter names, columns (n x k), bounds per parameter, and the
    sentence of physics."""

    effect: str
    location: str | None
    names: list
    X: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    explanation: str
    dC: list | None = None                   # structural terms: C_F increment [mm/N] per unit parameter
    hidden: int = 0                          # parameters chosen from a grid (creep's tau), counted in the BIC

    @property
    def n_params(self) -> int:
        return self.X.shape[1] + self.hidden


def spring_matrices(point_T, axis_T):
    """C_F increments [mm/N] per unit bending and torsion compliance [rad/(N mm)] of a rotational spring at
    ``point_T`` on a member along ``axis_T`` (in {T})."""
    r = -np.asarray(point_T, float)
    t = np.asarray(axis_T, float) / np.linalg.norm(axis_T)
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    b1 = np.cross(t, helper)
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(t, b1)
    Cb = sum(np.outer(np.cross(e, r), np.cross(e, r)) for e in (b1, b2))
    Ct = np.outer(np.cross(t, r), np.cross(t, r))
    return Cb, Ct


def spring_columns(data: RigData, point_T, axis_T) -> np.ndarray:
    """Columns for a rotational spring (bending s_b, torsion s_t [rad/(N mm)]) at ``point_T`` on a member
    along ``axis_T``: the extra displacement of component c under a force along a."""
    Cb, Ct = spring_matrices(point_T, axis_T)
    return np.column_stack([Cb[data.comp, data.axis] * data.F, Ct[data.comp, data.axis] * data.F])


def _kelvin_voigt(data: RigData, base: np.ndarray, tau: float) -> np.ndarray:
    """Creep of a Kelvin-Voigt element driven by the load history of each series (per unit phi): at every
    reading the creep relaxes towards the current elastic deflection with time constant ``tau`` [s]; it starts
    from zero at each series (the rod is remounted and the gauges zeroed)."""
    out = np.zeros_like(base)
    keys = data.axis * 4 + data.comp
    for k in np.unique(keys):
        idx = np.nonzero(keys == k)[0]
        idx = idx[np.argsort(data.t_abs[idx], kind="stable")]
        x = 0.0
        t_prev = data.t_abs[idx[0]]
        for i in idx:
            x = base[i] + (x - base[i]) * np.exp(-(data.t_abs[i] - t_prev) / tau)
            t_prev = data.t_abs[i]
            out[i] = x
    return out


#: time constants [s] of the creep hypotheses (a factor sqrt 2 apart); the chosen one is refined continuously
CREEP_TAU_GRID_S = tuple(float(v) for v in np.round(2.0 ** np.arange(0.0, 6.01, 0.5), 3))


def creep_term(data: RigData, base: np.ndarray, tau: float) -> Term:
    """Kelvin-Voigt creep with time constant ``tau`` [s] (its amplitude phi is the linear parameter)."""
    t = Term("creep", None, ["phi"], _kelvin_voigt(data, base, tau)[:, None], np.array([0.0]), np.array([1.0]),
             f"viscoelastic creep of the tubes or bonds: the deflection keeps growing during a hold at constant "
             f"load (time constant {tau:.3g} s), more at higher load", hidden=1)
    t.extra_tau = tau
    return t


def rig_terms(data: RigData, C_sim: np.ndarray, places: dict, tool_mm) -> list[Term]:
    """All candidate terms for ``data``; ``places``: {location: (point in {T}, member axis)} for joint springs."""
    base = C_sim[data.comp, data.axis] * data.F                       # the simulated displacement
    active = ~data.reference
    terms = []
    brake = np.where(data.unload, 1.0, -1.0) * active * C_sim[data.comp, data.axis] * data.sign
    terms.append(Term("friction", None, ["F_f_N"], brake[:, None], np.array([0.0]), np.array([50.0]),
                      "Coulomb friction in the rig's slides holds back F_f while loading and adds it while "
                      "unloading, splitting the branches by 2 F_f"))
    hanger = (data.mass > 0)
    terms.append(Term("tare", None, ["tare_kg"], (hanger * C_sim[data.comp, data.axis] * data.sign * G0)[:, None],
                      np.array([-5.0]), np.array([5.0]),
                      "a dead load missing from mass_kg (hanger or loading frame) offsets both branches equally"))
    terms.append(Term("compliance_scale", None, ["r_minus_1"], base[:, None], np.array([-0.8]), np.array([4.0]),
                      "every member uniformly softer or stiffer than simulated (a modulus off) scales all "
                      "compliance components by one factor r", dC=[np.asarray(C_sim, float)]))
    terms.append(Term("nonlinearity", None, ["beta_per_10N"], (base * np.abs(data.F) / 10.0)[:, None],
                      np.array([-1.0]), np.array([1.0]),
                      "a load-dependent stiffness bends the load-deflection line: the slope changes with the load"))
    # torsion of pipe I (axis z_T through the flange point): only components that twist pipe I
    flange = -np.asarray(tool_mm, float)
    terms.append(Term("torsion_compliance", "pipe_I", ["s_rad_per_Nmm"], spring_columns(data, flange, [0, 0, 1])[:, 1:],
                      np.array([0.0]), np.array([1e-2]),
                      "pipe I twists more than simulated (a low laminate shear modulus): excess compliance only in "
                      "the components that twist pipe I", dC=[spring_matrices(flange, [0, 0, 1])[1]]))
    for loc, (pt, ax) in places.items():
        Cb, Ct = spring_matrices(pt, ax)
        X = spring_columns(data, pt, ax)
        names, dC = ["s_bend_rad_per_Nmm", "s_torsion_rad_per_Nmm"], [Cb, Ct]
        if np.abs(Ct).max() < 1e-9 * np.abs(Cb).max():
            # the member points at the ball: its torsion moves no reading and cannot be identified
            X, names, dC = X[:, :1], names[:1], dC[:1]
        terms.append(Term("joint_compliance", loc, names, X, np.zeros(len(names)), np.full(len(names), 1e-2),
                          f"a compliant joint (bond, clamp or thread) at {loc} acts as a rotational spring whose "
                          f"excess compliance grows with the lever from {loc} to the ball", dC=dC))
    for tau in CREEP_TAU_GRID_S:
        terms.append(creep_term(data, base, float(tau)))
    comps = sorted(set(data.comp.tolist()))
    for c in comps:
        others = [j for j in comps if j != c]
        for j in others:
            # reading of sensor c picks up eps x the true displacement along j (the simulated one)
            col = np.zeros(data.y.size)
            m = data.comp == c
            col[m] = C_sim[j, data.axis[m]] * data.F[m]
            terms.append(Term("crosstalk", f"sensor:{'xyz'[c]}", [f"eps_{'xyz'[j]}_rad"], col[:, None],
                              np.array([-0.2]), np.array([0.2]),
                              f"the {'xyz'[c]} gauge is not aligned with its axis and reads a fraction of the "
                              f"{'xyz'[j]} displacement, which the rod's compliance cannot produce"))
    Xt = np.column_stack([(data.comp == c) * data.t_series for c in comps])
    terms.append(Term("drift", "time", [f"rate_{'xyz'[c]}_mm_per_s" for c in comps], Xt, np.full(len(comps), -1.0),
                      np.full(len(comps), 1.0), "a zero drift of the gauges (thermal or electronic) that follows "
                                                 "time, independent of the load"))
    if np.isfinite(data.temp).all() and np.ptp(data.temp) > 0.05:
        # relative to the series start (the gauges are zeroed there)
        XT = np.column_stack([(data.comp == c) * data.temp_rel for c in comps]) if hasattr(data, "temp_rel") else None
        if XT is not None:
            terms.append(Term("drift", "temp", [f"{'xyz'[c]}_mm_per_K" for c in comps], XT, np.full(len(comps), -1.0),
                              np.full(len(comps), 1.0), "a zero drift of the gauges that follows the temperature, "
                                                        "independent of the load"))
    return terms
