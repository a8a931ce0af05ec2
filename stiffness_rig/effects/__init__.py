"""Rig effects: one module per effect of ``contract/effects.md`` (subject ``rig``) plus rodlab's additions,
each with its forward model, parameter schema, hypotheses and wording; one registry keyed by
:class:`rodlab.core.enums.RigEffect`.

Adding an effect: a new value of ``RigEffect``, a module with a :class:`RigEffectModel` subclass, one line in
:data:`RIG_EFFECTS` and a test. The simulator, ``rodlab rig simulate --effect``, the diagnosis, its report and
the docs (``python scripts/gen_cli_docs.py`` writes the table of docs/formats.md) all take it from here.
"""
from __future__ import annotations

from rodlab.core.enums import RigEffect

from ..errors import RigError
from .base import HypothesisContext, RigEffectModel, RigState
from .compliance_scale import ComplianceScale
from .creep import CREEP_TAU_GRID_S, Creep, creep_hypothesis
from .crosstalk import Crosstalk
from .drift import Drift
from .friction import Friction
from .joint_compliance import JointCompliance
from .load_hysteresis import LoadHysteresis
from .nonlinearity import Nonlinearity
from .springs import joint_places, spring_columns, spring_compliance, spring_matrices
from .tare import Tare
from .torsion_compliance import TorsionCompliance

__all__ = ["RIG_EFFECTS", "rig_effect", "complete_effects", "rig_hypotheses", "RigEffectModel",
           "HypothesisContext", "RigState", "creep_hypothesis", "CREEP_TAU_GRID_S", "joint_places",
           "spring_matrices", "spring_compliance", "spring_columns", "vocabulary_markdown"]

#: every rig effect, in the order the forward model applies them and the diagnosis lists its hypotheses
RIG_EFFECTS: dict[RigEffect, RigEffectModel] = {m.effect: m for m in (
    Friction(), Tare(), ComplianceScale(), Nonlinearity(), TorsionCompliance(), JointCompliance(), Creep(),
    Crosstalk(), Drift(), LoadHysteresis())}


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
