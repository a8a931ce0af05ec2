"""``creep``: Kelvin-Voigt creep of the tubes or bonds — extra deflection phi C F approached with time constant
tau [s] after every change of load; it starts from zero at each series (the rod is remounted, gauges zeroed)."""
from __future__ import annotations

import numpy as np

from rodlab.core.hypothesis import Hypothesis, ParamSpec

from ..errors import RigError
from .base import RigEffectModel

__all__ = ["Creep", "creep_hypothesis", "CREEP_TAU_GRID_S"]

#: time constants [s] of the creep hypotheses (a factor sqrt 2 apart); the chosen one is refined continuously
CREEP_TAU_GRID_S = tuple(float(v) for v in np.round(2.0 ** np.arange(0.0, 6.01, 0.5), 3))


class Creep(RigEffectModel):
    effect = "creep"
    order = 70
    params = (ParamSpec("phi", "-", "creep deflection at equilibrium over the elastic one"),
              ParamSpec("tau_s", "s", "creep time constant", 6.0, magnitude=False))
    example = {"phi": 0.02}
    physics = "viscoelastic creep of tubes or bonds"
    signature = "deflection grows during a constant-load hold, faster at higher load"
    confirm = "hold one load 3-5 times longer: the deflection should keep growing with the fitted time constant"

    def check(self, p: dict) -> None:
        if not p["tau_s"] > 0:
            raise RigError(f"effect creep: tau_s must be > 0 s, got {p['tau_s']!r}", key="creep.tau_s")

    def deflection(self, x, C, F, t, state, p):
        phi, tau = self.value(p, "phi"), float(p["tau_s"])
        target = phi * (C @ F)
        dt = 0.0 if state.t_last is None else max(t - state.t_last, 0.0)
        state.creep = target + (state.creep - target) * np.exp(-dt / tau)
        return x + state.creep

    def hypotheses(self, data, ctx) -> list[Hypothesis]:
        columns = _kelvin_voigt(data, ctx.base, np.array(CREEP_TAU_GRID_S))
        return [creep_hypothesis(data, ctx.base, tau, columns[:, k]) for k, tau in enumerate(CREEP_TAU_GRID_S)]


def _kelvin_voigt(data, base: np.ndarray, taus: np.ndarray) -> np.ndarray:
    """Creep per unit phi of every sample, shape=(n, len(taus)), driven by the load history of each series: at
    every reading it relaxes towards the current elastic deflection ``base`` with each time constant ``taus``
    [s] (all of them at once: one pass over the readings)."""
    taus = np.atleast_1d(np.asarray(taus, float))
    out = np.zeros((base.size, taus.size))
    keys = data.zero_groups                    # per series: the rod is remounted, its creep starts afresh
    for k in np.unique(keys):
        idx = np.nonzero(keys == k)[0]
        idx = idx[np.argsort(data.t_abs[idx], kind="stable")]
        dt = np.diff(data.t_abs[idx], prepend=data.t_abs[idx[0]])
        keep = np.exp(-dt[:, None] / taus[None, :])                   # what is left of the last creep, per tau
        pull = (1.0 - keep) * base[idx][:, None]
        x = np.zeros(taus.size)
        for i, row in enumerate(idx):
            x = x * keep[i] + pull[i]
            out[row] = x
    return out


def creep_hypothesis(data, base: np.ndarray, tau: float, column: np.ndarray | None = None) -> Hypothesis:
    """Kelvin-Voigt creep with time constant ``tau`` [s]; its amplitude phi is the linear parameter (``column``:
    its response per unit phi, shape=(n,), when already computed)."""
    X = (_kelvin_voigt(data, base, tau)[:, 0] if column is None else column)[:, None]
    return Hypothesis(Creep.effect, None, ["phi"], X, [0.0], [1.0],
                      f"viscoelastic creep of the tubes or bonds: the deflection keeps growing during a hold at "
                      f"constant load (time constant {tau:.3g} s), more at higher load", hidden=1,
                      settings={"tau_s": float(tau)})
