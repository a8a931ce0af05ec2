"""Rig effects: one module per effect of ``contract/effects.md`` (subject ``rig``) plus rodlab's additions,
each with its forward model, parameter schema, hypotheses and wording; one registry, :data:`RIG_EFFECTS`, keyed
by :data:`RigEffect`, the Enum of the effect IDs it found.

Adding an effect is one module in this package with a :class:`RigEffectModel` subclass that names its ID and
its place (``effect = "friction"``, ``order = 10``), and its test: :func:`discover` (run on import) finds every
module of the package, builds :data:`RigEffect` from their IDs and orders the registry by ``order``. The
simulator, ``rodlab rig simulate --effect``, the diagnosis, its report and the docs (``python
scripts/gen_cli_docs.py`` writes the table of docs/formats.md) all take it from here.
"""
from __future__ import annotations

from rodlab.core.registry import refill_id_registry

from ..errors import RigError
from .base import HypothesisContext, RigEffectModel, RigState
from .creep import CREEP_TAU_GRID_S, creep_hypothesis, held_creep_share, two_term_creep_hypothesis
from .springs import joint_places, spring_columns, spring_compliance, spring_matrices

__all__ = ["RIG_EFFECTS", "RigEffect", "discover", "rig_effect", "complete_effects", "rig_hypotheses",
           "RigEffectModel", "HypothesisContext", "RigState", "creep_hypothesis", "two_term_creep_hypothesis", "held_creep_share",
           "CREEP_TAU_GRID_S", "joint_places",
           "spring_matrices", "spring_compliance", "spring_columns", "vocabulary_markdown"]

_ENUM_DOC = """Effects of the subject ``rig`` (contract ``effects.md``, plus rodlab's additions): physics of the rod or
the stiffness rig left out of a simulated compliance, in registry order. Built by
:func:`rodlab.stiffness_rig.effects.discover` from the effect modules of :mod:`rodlab.stiffness_rig.effects`
(each has its forward model, parameters with units, hypotheses and wording)."""

#: every rig effect, in the order the forward model applies them and the diagnosis lists its hypotheses
#: (their ``order``); filled by :func:`discover`
RIG_EFFECTS: dict = {}


def discover() -> type:
    """Find the rig effects: every :class:`RigEffectModel` subclass the modules of this package define (a
    folder added to its ``__path__`` too), sorted by ``order``; (re)build :data:`RigEffect` from their IDs, make
    each class's ``effect`` its member and refill :data:`RIG_EFFECTS` in place. Run on import; run it again
    after changing the package's ``__path__`` (the same modules give back the same Enum and models). Returns
    :data:`RigEffect`."""
    global RigEffect
    RigEffect = refill_id_registry(__name__, RigEffectModel, RIG_EFFECTS, "RigEffect", _ENUM_DOC, "rig effect")
    return RigEffect


#: the rig effect IDs (contract spelling), one member per effect module, in registry order
RigEffect = discover()


def rig_effect(name) -> RigEffectModel:
    """The effect called ``name`` (its ID); :class:`RigError` listing the known ones otherwise."""
    try:
        return RIG_EFFECTS[RigEffect.parse(name, "rig effect")]
    except ValueError as e:
        raise RigError(str(e), key="effect") from None


def complete_effects(effects: dict) -> dict:
    """{RigEffect: full parameters} from {name: given parameters}, in registry order (see
    :meth:`RigEffectModel.complete`)."""
    given = {rig_effect(k).effect: v for k, v in dict(effects).items()}
    return {e: RIG_EFFECTS[e].complete(given[e] or {}) for e in RIG_EFFECTS if e in given}


def rig_hypotheses(data, ctx: HypothesisContext) -> list:
    """The diagnosis library: every effect's hypotheses for the samples ``data``, in registry order."""
    return [h for m in RIG_EFFECTS.values() for h in m.hypotheses(data, ctx)]


def vocabulary_markdown() -> str:
    """The rig effect vocabulary as the Markdown table of docs/formats.md (generated: ``scripts/gen_cli_docs.py``)."""
    rows = ["| effect | physics left out | signature in the data | location | parameters (simulator and report) |",
            "|---|---|---|---|---|"]
    for e, m in RIG_EFFECTS.items():
        params = m.params_markdown()
        where = ", ".join(f"`{loc}`" for loc in m.locations) or "`null`"
        rows.append(f"| `{e.value}` | {m.physics} | {m.signature} | {where} | {params} |")
    return "\n".join(rows)
