"""Selection with the rig's effects acting on the rod and the load as found (an exact simulation).

The library's columns are linear in the effects' parameters about the simulated rod and the recorded loads. Two
products are left out that way, and a look-alike takes them: the rig's effects (friction, creep, non-linearity,
crosstalk ...) act through the rod's compliance as it is, structural excess included (the friction of a rod whose
pipe I twists more also twists it more; left out, a joint spring on pipe I took that part), and on the load as it
is, a missing dead load included (a load non-linearity on top of a tare is a compliance scale of 1 + 2 beta tare g0
/ 10 N; left out, a `compliance_scale` took it). So after a selection that chose a structural term or a tare, the
columns are rebuilt on the compliance and the load it gives and the selection runs again, until the terms chosen
are those the columns were built on (:func:`select_as_found`). The structural terms' own columns stay on the
simulated compliance: their parameters are changes of it.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from rodlab.core.units import G0
from rodlab.stiffness_rig.effects import RIG_EFFECTS, HypothesisContext
from rodlab.stiffness_rig.samples import RigSamples

from .rig_outside import outside_hypotheses
from .rig_select import subset_ls
from .rig_steps import select_refining_creep

__all__ = ["select_as_found"]

#: at most this many selections: the first self-consistent one is kept, else the first
PASSES = 3


def _library(data: RigSamples, C_sim: np.ndarray, C_other: np.ndarray, places: dict, tool: np.ndarray,
                  data_other: RigSamples | None = None) -> list:
    """The structural effects' hypotheses on the simulated compliance ``C_sim`` and the samples ``data``, the
    other effects' and the gauges' on ``C_other`` and ``data_other`` (the rod and the loads as found so far;
    default ``data``)."""
    d = data if data_other is None else data_other
    ctx_sim = HypothesisContext(C_sim, C_sim[data.comp, data.axis] * data.F, places, tool)
    ctx = HypothesisContext(C_other, C_other[d.comp, d.axis] * d.F, places, tool)
    vocabulary = [h for m in RIG_EFFECTS.values()
                  for h in (m.hypotheses(data, ctx_sim) if m.structural else m.hypotheses(d, ctx))]
    nuisance = [h.X for h in vocabulary if not h.dC]       # the rig's own effects: a slip is sought without them too
    return vocabulary + outside_hypotheses(d, ctx.base, np.column_stack(nuisance) if nuisance else None)


def select_as_found(data: RigSamples, C_sim: np.ndarray, places: dict, tool: np.ndarray, prep, r0: np.ndarray,
                    sigma: float, max_terms: int, folds):
    """Select (:func:`~.rig_steps.select_refining_creep`) with the columns rebuilt on the rod and the load as
    found until self-consistent (the module docstring). Returns (library, its SubsetLS, the chosen indices, their
    coefficients, the residual sum of squares)."""
    runs, C_other, data_other, built_on = [], C_sim, data, ()
    for _ in range(PASSES):
        library = [prep(t) for t in _library(data, C_sim, C_other, places, tool, data_other)]
        library, ls, S = select_refining_creep(library, subset_ls(library, r0, folds), data_other,
                                               C_other[data.comp, data.axis] * data_other.F, r0, prep, sigma,
                                               max_terms, folds)
        coef, rss = ls.fit(S)
        runs.append((library, ls, S, coef, rss))
        chosen = tuple(sorted((str(library[j].effect), str(library[j].location)) for j in S
                              if library[j].dC or library[j].effect == "tare"))
        if chosen == built_on:
            return runs[-1]
        C_other, tare_kg = _as_found(C_sim, library, S, coef)
        data_other = _with_tare(data, tare_kg)
        built_on = chosen
    return runs[0]


def _as_found(C_sim: np.ndarray, library, S: tuple, coef: np.ndarray) -> tuple[np.ndarray, float]:
    """``C_sim`` plus the chosen structural terms' increments [mm/N], and the chosen tare [kg] (0 without one)."""
    C, k, tare = np.array(C_sim, float), 0, 0.0
    for j in S:
        t = library[j]
        v = coef[k:k + t.X.shape[1]]
        if t.dC:
            for val, dC in zip(v, t.dC):
                C = C + val * dC
        elif t.effect == "tare":
            tare = float(v[0])
        k += t.X.shape[1]
    return C, tare


def _with_tare(data: RigSamples, tare_kg: float) -> RigSamples:
    """The samples with the tare's weight in the load of every hold a mass hangs in (as the tare effect puts it)."""
    if tare_kg == 0.0:
        return data
    return dataclasses.replace(data, F=data.F + (data.mass > 0) * data.sign * tare_kg * G0)
