"""``creep``: Kelvin-Voigt creep of the tubes or bonds — extra deflection phi C F approached with time constant
tau [s] after every change of load; it starts from zero at each series (the rod is remounted, gauges zeroed).
A second Kelvin-Voigt term (``phi_2``, ``tau_2_s``: a laminate's fast and a bond's slow creep) adds its own."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["Creep", "kelvin_voigt", "load_step_at", "creep_hypothesis", "two_term_creep_hypothesis",
           "CREEP_TAU_GRID_S", "SETTLING_TAU_S", "CREEP_PHI_PLAUSIBLE", "held_creep_share", "relax"]

#: a creep time constant below this [s] is more likely a hung weight settling than a laminate's or bond's creep
SETTLING_TAU_S = 1.0
#: a creep deflection beyond this share of the elastic one is no laminate's or bond's at a rig's loads
CREEP_PHI_PLAUSIBLE = 0.15
#: time constants [s] of the creep hypotheses (a factor sqrt 2 apart); the chosen one is refined continuously
CREEP_TAU_GRID_S = tuple(float(v) for v in np.round(2.0 ** np.arange(0.0, 6.01, 0.5), 3))



class Creep(RigEffectModel):
    effect = "creep"
    order = 70
    params = (ParamSpec("phi", "-", "creep deflection at equilibrium over the elastic one"),
              ParamSpec("tau_s", "s", "creep time constant", 6.0, magnitude=False),
              ParamSpec("phi_2", "-", "a second creep term's deflection at equilibrium over the elastic one "
                                      "(optional)"),
              ParamSpec("tau_2_s", "s", "the second term's time constant (with phi_2)", magnitude=False),
              ParamSpec("load_step_at", "-", "when the load changes between holds, as a share of the gap: 0 right "
                                             "after the previous hold's last reading, 1 as the new hold's readings "
                                             "start", magnitude=False))
    example = {"phi": 0.02}
    physics = "viscoelastic creep of tubes or bonds"
    signature = "deflection grows during a constant-load hold, faster at higher load"
    confirm = "hold one load 3-5 times longer: the deflection should keep growing with the fitted time constant"

    def check(self, p: dict) -> None:
        if not p["tau_s"] > 0:
            raise RigError(f"effect creep: tau_s must be > 0 s, got {p['tau_s']!r}", key="creep.tau_s")
        if p.get("tau_2_s") is not None and p.get("phi_2") is None:
            raise RigError("effect creep: tau_2_s is the second term's time constant: give its phi_2 too",
                           key="creep.phi_2")
        if p.get("phi_2") is not None and not (p.get("tau_2_s") or 0) > 0:
            raise RigError(f"effect creep: phi_2 needs its time constant tau_2_s > 0 s, got {p.get('tau_2_s')!r}",
                           key="creep.tau_2_s")

    def caution(self, p: dict) -> str | None:
        """A time constant under :data:`SETTLING_TAU_S` is more likely a hung weight settling; a creep beyond
        :data:`CREEP_PHI_PLAUSIBLE` of the elastic deflection more than a laminate or a sound bond creeps."""
        terms = [(float(phi), float(tau)) for phi, tau in ((p.get("phi"), p.get("tau_s")),
                                                           (p.get("phi_2"), p.get("tau_2_s")))
                 if phi is not None and tau is not None]
        fast = [(phi, tau) for phi, tau in terms if tau < SETTLING_TAU_S]
        if fast:
            phi, tau = fast[0]
            return (f"a creep with a {tau:.3g} s time constant (phi {phi:.3g}) is more likely each load settling (the "
                    f"weight swinging or still being lowered) than the rod's creep (laminates and bonds creep over "
                    f"seconds to minutes): leave the first seconds of each hold out or wait for the readings to settle "
                    f"(`rig acquire` records its settling apart and says so in its header)")
        large = [(phi, tau) for phi, tau in terms if abs(phi) > CREEP_PHI_PLAUSIBLE]
        if large:
            phi, tau = large[0]
            return (f"a creep of {phi:.3g} of the elastic deflection (time constant {tau:.3g} s) is more than a laminate "
                    f"or a sound bond creeps at a rig's loads (a few %): check the bonds and clamps for a joint slipping "
                    f"or yielding under load")
        return None

    def deflection(self, x, C, F, t, state, p):
        dt = 0.0 if state.t_last is None else max(t - state.t_last, 0.0)
        terms = [(self.value(p, "phi"), float(p["tau_s"]))]
        if p.get("phi_2") is not None:
            terms.append((self.value(p, "phi_2"), float(p["tau_2_s"])))
        late = min(max(self.value(p, "load_step_at"), 0.0), 1.0)
        for k, (phi, tau) in enumerate(terms):
            target = phi * (C @ F)
            if late and not np.allclose(target, state.creep_target[k]):      # the old load until the change
                old = state.creep_target[k]
                state.creep[k] = old + (state.creep[k] - old) * np.exp(-late * dt / tau)
                dt_k = (1.0 - late) * dt
            else:
                dt_k = dt
            state.creep[k] = target + (state.creep[k] - target) * np.exp(-dt_k / tau)
            state.creep_target[k] = target
        return x + state.creep.sum(axis=0)

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        step_at = load_step_at(data)
        columns = kelvin_voigt(data, ctx.base, np.array(CREEP_TAU_GRID_S), step_at)
        return [creep_hypothesis(data, ctx.base, tau, columns[:, k], step_at) for k, tau in enumerate(CREEP_TAU_GRID_S)]


def kelvin_voigt(data, base: np.ndarray, taus: np.ndarray, step_at: float = 0.0) -> np.ndarray:
    """Creep per unit phi of every sample, shape=(n, len(taus)), driven by the load history of each series: at
    every reading it relaxes towards the current elastic deflection ``base`` with each time constant ``taus``
    [s]: x_i = x_(i-1) exp(-dt_i / tau) + (1 - exp(-dt_i / tau)) base_i, summed in closed form
    (:func:`relax`). ``step_at``: when the load changed between two holds, as a share of the time from the
    previous hold's last reading to the new hold's first (0: right after the previous hold, 1: at the new hold's
    first reading, the weight hung as its recording starts)."""
    taus = np.atleast_1d(np.asarray(taus, float))
    out = np.zeros((base.size, taus.size))
    keys = data.zero_groups                    # per series: the rod is remounted, its creep starts afresh
    for k in np.unique(keys):
        idx = np.nonzero(keys == k)[0]
        idx = idx[np.argsort(data.t_abs[idx], kind="stable")]
        t, b, real = ((data.t_abs[idx], base[idx], slice(None)) if not step_at else
                      _with_load_steps(data.t_abs[idx], base[idx], data.step[idx], data.t_hold[idx], step_at))
        for m, tau in enumerate(taus):
            out[idx, m] = relax(t / tau, b)[real]
    return out


def load_step_at(data) -> float:
    """When the load changed between holds (``load_step_at``), from what the recording shows: 1 (as the new hold's
    recording started) where readings were left out at the holds' starts, a settling the readings showed or the
    samples `rig acquire` records while a hold settles, both after the weight was hung; else 0 (before the hold's
    first reading, which is settled: rodlab's simulator). A paper-rod trial hung each weight as its hold began:
    read with 0, its creep came out 2x and the export 3.5 % stiff. With the linear compliance fitted beside it the
    data cannot tell the two apart (the creep's share trades with the compliance), so the recording decides."""
    step, t_hold = getattr(data, "step", None), getattr(data, "t_hold", None)
    if step is None or t_hold is None or not np.size(step):
        return 0.0
    steps, where = np.unique(np.asarray(step), return_inverse=True)
    first = np.full(steps.size, np.inf)
    np.minimum.at(first, where, np.asarray(t_hold, float))    # each hold's first reading on any gauge (a gauge
    return 1.0 if float(np.median(first)) > 0.0 else 0.0     # blank on a hold's first row is no readings left out


def _with_load_steps(t: np.ndarray, base: np.ndarray, step: np.ndarray, t_hold: np.ndarray, step_at: float):
    """(times, loads, the real samples' places) with a sample inserted at each change of hold, ``step_at`` of the
    way from the previous reading to the new hold's start (its first reading's time less ``t_hold``: where a
    settling was left out, the hold's first recorded reading), carrying the previous load: the load's change."""
    real = np.arange(t.size)
    if not step_at or t.size < 2:
        return t, base, real
    new = np.flatnonzero(np.diff(step) != 0) + 1               # each hold's first reading
    start = np.clip(t[new] - t_hold[new], t[new - 1], t[new])
    at = t[new - 1] + min(float(step_at), 1.0) * (start - t[new - 1])
    at = np.minimum(at, np.nextafter(t[new], -np.inf))
    t2 = np.insert(t, new, at)
    b2 = np.insert(base, new, base[new - 1])
    real = np.arange(t.size) + np.searchsorted(new, np.arange(t.size), side="right")
    return t2, b2, real


#: the span of scaled time [time constants] summed in one block (exp(500) ~ 1e217 stays finite)
_BLOCK = 500.0


def relax(s: np.ndarray, base: np.ndarray) -> np.ndarray:
    """The recursion x_i = x_(i-1) e^-(s_i - s_(i-1)) + (1 - e^-(s_i - s_(i-1))) base_i from x = 0, over times
    ``s`` in time constants (sorted), as x_i = sum_(k <= i) pull_k e^-(s_i - s_k): a cumulative sum per block of
    :data:`_BLOCK` time constants, the state carried from block to block."""
    pull = -np.expm1(-np.diff(s, prepend=s[:1])) * base
    out = np.empty_like(pull)
    x, s_last = 0.0, s[0]
    edges = np.searchsorted(s, s[0] + _BLOCK * np.arange(1, int((s[-1] - s[0]) // _BLOCK) + 2))
    start = 0
    for stop in np.append(edges, s.size):
        if stop <= start:
            continue
        w = np.exp(s[start:stop] - s[start])
        out[start:stop] = (np.cumsum(pull[start:stop] * w) + x * np.exp(s_last - s[start])) / w
        x, s_last, start = out[stop - 1], s[stop - 1], stop
    return out


def creep_hypothesis(data, base: np.ndarray, tau: float, column: np.ndarray | None = None,
                     step_at: float = 0.0) -> Hypothesis:
    """Kelvin-Voigt creep with time constant ``tau`` [s], the load changed ``step_at`` of the way between holds
    (:func:`kelvin_voigt`); its amplitude phi is the linear parameter (``column``: its response per unit phi,
    shape=(n,), when already computed)."""
    X = (kelvin_voigt(data, base, tau, step_at)[:, 0] if column is None else column)[:, None]
    when = "" if not step_at else ", the weights changed as each hold's readings start"
    return Hypothesis(Creep.effect, None, ["phi"], X, [0.0], [1.0],
                      f"viscoelastic creep of the tubes or bonds: the deflection keeps growing during a hold at "
                      f"constant load (time constant {tau:.3g} s{when}), more at higher load", hidden=1,
                      settings={"tau_s": float(tau)} | ({"load_step_at": float(step_at)} if step_at else {}))


def two_term_creep_hypothesis(data, base: np.ndarray, tau: float, tau_2: float, step_at: float = 0.0) -> Hypothesis:
    """Kelvin-Voigt creep of two terms, time constants ``tau`` and ``tau_2`` [s] (a laminate's fast and a bond's
    slow creep), the load changed ``step_at`` of the way between holds (:func:`kelvin_voigt`); their amplitudes phi
    and phi_2 are the linear parameters, the two time constants hidden."""
    X = kelvin_voigt(data, base, np.array([tau, tau_2]), step_at)
    fast, slow = sorted((tau, tau_2))
    return Hypothesis(Creep.effect, None, ["phi", "phi_2"], X, [0.0, 0.0], [1.0, 1.0],
                      f"viscoelastic creep of the tubes or bonds in two terms: the deflection keeps growing during a "
                      f"hold at constant load, part of it within seconds (time constant {fast:.3g} s) and part "
                      f"slowly ({slow:.3g} s), more at higher load", hidden=2,
                      settings={"tau_s": float(tau), "tau_2_s": float(tau_2)}
                      | ({"load_step_at": float(step_at)} if step_at else {}))


#: a creep term of a time constant up to this share of a hold is complete within it: part of the compliance
FAST_CREEP_HOLD_SHARE = 1.0 / 3.0


def held_creep_share(p: dict, hold_s: float) -> tuple[float, float]:
    """(fast, slow): the creep of a finding's terms (``p``: its parameters) as shares of the elastic deflection,
    those complete within a hold of ``hold_s`` seconds (a time constant up to :data:`FAST_CREEP_HOLD_SHARE` of
    it: no reading sees the load's first instant, so their creep is the rod's compliance) and the rest."""
    fast = slow = 0.0
    for phi, tau in ((p.get("phi"), p.get("tau_s")), (p.get("phi_2"), p.get("tau_2_s"))):
        if phi is None or tau is None or not float(tau) > 0:
            continue
        if float(tau) <= FAST_CREEP_HOLD_SHARE * hold_s:
            fast += float(phi)
        else:
            slow += float(phi)
    return fast, slow
