"""Campaign effects: one module per effect of ``contract/effects.md`` (subject ``campaign``), each with its part
of the campaign simulator, its parameter schema, its hypotheses for the diagnosis, how a finding enters the
re-identification, its wording and its remedy; one registry, :data:`CAMPAIGN_EFFECTS`, keyed by
:data:`CampaignEffect`, the Enum of the effect IDs it found.

Adding an effect is one module in this package with a :class:`CampaignEffectModel` subclass that names its ID
and its place (``effect = "outliers"``, ``order = 50``), and its test: :func:`discover` (run on import) finds
every module of the package, builds :data:`CampaignEffect` from their IDs and orders the registry by
``order``. ``simulate_campaign(effects=...)``, ``rodlab simulate-campaign --effect``, ``rodlab diagnose
--campaign``, the remedies ``rodlab calibrate`` prints and the table of docs/formats.md take it from here.
"""
from __future__ import annotations

from rodlab.core.registry import refill_id_registry

from ..errors import CalibrationError
from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis
from .periodic_joint_error import correct_joints
from .rod_deflection import generic_rod

__all__ = ["CAMPAIGN_EFFECTS", "CampaignEffect", "discover", "campaign_effect", "complete_campaign_effects",
           "campaign_hypotheses", "CampaignEffectModel", "CampaignContext", "Refit", "hypothesis", "correct_joints",
           "generic_rod", "campaign_vocabulary_markdown"]

_ENUM_DOC = """Effects of the subject ``campaign`` (contract ``effects.md``): physics left out of the identified model,
in registry order. Built by :func:`rodlab.calibrate.effects.discover` from the effect modules of
:mod:`rodlab.calibrate.effects`."""

#: every campaign effect, in the order the simulator applies them and the diagnosis lists its hypotheses (their
#: ``order``, which also breaks ties between equally good hypotheses: give a new effect a place after the others);
#: filled by :func:`discover`
CAMPAIGN_EFFECTS: dict = {}


def discover() -> type:
    """Find the campaign effects: every :class:`CampaignEffectModel` subclass the modules of this package define
    (a folder added to its ``__path__`` too), sorted by ``order``; (re)build :data:`CampaignEffect` from their
    IDs, make each class's ``effect`` its member and refill :data:`CAMPAIGN_EFFECTS` in place. Run on import;
    run it again after changing the package's ``__path__`` (the same modules give back the same Enum and
    models). Returns :data:`CampaignEffect`."""
    global CampaignEffect
    CampaignEffect = refill_id_registry(__name__, CampaignEffectModel, CAMPAIGN_EFFECTS, "CampaignEffect", _ENUM_DOC,
                                        "campaign effect")
    return CampaignEffect


#: the campaign effect IDs (contract spelling), one member per effect module, in registry order
CampaignEffect = discover()


def campaign_effect(name) -> CampaignEffectModel:
    """The effect called ``name`` (its ID); :class:`CalibrationError` listing the known ones otherwise."""
    try:
        return CAMPAIGN_EFFECTS[CampaignEffect.parse(name, "campaign effect")]
    except ValueError as e:
        raise CalibrationError(str(e), key="effect") from None


def complete_campaign_effects(effects) -> list[tuple[CampaignEffectModel, dict]]:
    """[(model, full parameters)] in registry order from ``{name: given}`` or ``[(name, given), ...]`` (an
    effect may appear more than once in the list form, e.g. two wrong fixture poses)."""
    items = list(effects.items()) if hasattr(effects, "items") else list(effects or [])
    done = [(campaign_effect(name), given) for name, given in items]
    done = [(m, m.complete(given or {})) for m, given in done]
    for i, (m, p) in enumerate(done):
        for m2, p2 in done[:i]:
            if m2 is m and (not m.repeatable or m.same_place(p, p2)):
                raise CalibrationError(f"effect {m.effect} is given twice{' at the same place' if m.repeatable else ''}"
                                       f"; give it once", key=str(m.effect))
    order = list(CAMPAIGN_EFFECTS)
    return sorted(done, key=lambda mp: order.index(mp[0].effect))


def campaign_hypotheses(ctx: CampaignContext) -> list:
    """The diagnosis library: every (not per-point) effect's hypotheses for the campaign ``ctx``."""
    return [h for m in CAMPAIGN_EFFECTS.values() if not m.per_point for h in m.hypotheses(ctx)]


def campaign_vocabulary_markdown() -> str:
    """The campaign effect vocabulary as the Markdown table of docs/formats.md (``scripts/gen_cli_docs.py``)."""
    rows = ["| effect | physics left out | signature in the residuals | location | simulator parameters "
            "(`simulate-campaign --effect`) | reported parameters |", "|---|---|---|---|---|---|"]
    for e, m in CAMPAIGN_EFFECTS.items():
        where = ", ".join(f"`{loc}`" for loc in m.locations)
        rows.append(f"| `{e.value}` | {m.physics} | {m.signature} | {where} | {m.params_markdown()} | {m.reported} |")
    return "\n".join(rows)
