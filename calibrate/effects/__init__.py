"""Campaign effects: one module per effect of ``contract/effects.md`` (subject ``campaign``), each with its part
of the campaign simulator, its parameter schema, its hypotheses for the diagnosis, how a finding enters the
re-identification, its wording and its remedy; one registry keyed by :class:`rodlab.core.enums.CampaignEffect`.

Adding an effect: a new value of ``CampaignEffect``, a module with a :class:`CampaignEffectModel` subclass,
one line in :data:`CAMPAIGN_EFFECTS` and a test. ``simulate_campaign(effects=...)``, ``rodlab
simulate-campaign --effect``, ``rodlab diagnose --campaign``, the remedies ``rodlab calibrate`` prints and the
table of docs/formats.md take it from here.
"""
from __future__ import annotations

from rodlab.core.enums import CampaignEffect

from ..errors import CalibrationError
from .base import CampaignContext, CampaignEffectModel, Refit, hypothesis
from .device_axes import DeviceAxes
from .fixture_pose import FixturePose
from .outliers import Outliers
from .periodic_joint_error import PeriodicJointError, correct_joints
from .rod_deflection import RodDeflection, generic_rod
from .thermal_drift import ThermalDrift

__all__ = ["CAMPAIGN_EFFECTS", "campaign_effect", "complete_campaign_effects", "campaign_hypotheses",
           "CampaignEffectModel", "CampaignContext", "Refit", "hypothesis", "correct_joints", "generic_rod",
           "campaign_vocabulary_markdown"]

#: every campaign effect, in the order the simulator applies them and the diagnosis lists its hypotheses (the
#: order also breaks ties between equally good hypotheses: append new effects at the end)
CAMPAIGN_EFFECTS: dict[CampaignEffect, CampaignEffectModel] = {m.effect: m for m in (
    FixturePose(), RodDeflection(), PeriodicJointError(), ThermalDrift(), Outliers(), DeviceAxes())}


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
