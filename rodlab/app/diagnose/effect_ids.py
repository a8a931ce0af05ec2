"""What a diagnosis finding's ``effect`` is: a rig effect, a campaign effect, or a finding that names none.

The rig effects' and the campaign effects' IDs are their registries' Enums (``RigEffect`` in
:mod:`rodlab.stiffness_rig.effects`, ``CampaignEffect`` in :mod:`rodlab.calibrate.effects`: built from the effect
modules they find), the others :class:`~rodlab.core.enums.FindingKind`; the application is the lowest layer that
sees all three, so the union and its parser live here.
"""
from __future__ import annotations

from typing import Union

from rodlab.calibrate import effects as campaign_effects
from rodlab.core.enums import FindingKind
from rodlab.core.errors import RodlabError, did_you_mean
from rodlab.stiffness_rig import effects as rig_effects

__all__ = ["EffectId", "effect_id_kinds", "parse_effect_id"]

#: what a diagnosis finding's ``effect`` is: a rig effect, a campaign effect, or a finding that names none
EffectId = Union[rig_effects.RigEffect, campaign_effects.CampaignEffect, FindingKind]


def effect_id_kinds() -> tuple:
    """The Enums a finding's effect comes from, as the registries have them now (a rediscovery rebuilds them)."""
    return rig_effects.RigEffect, campaign_effects.CampaignEffect, FindingKind


def parse_effect_id(value) -> EffectId:
    """A finding's effect ID from its contract spelling (rig effects, campaign effects, ``model_form``,
    ``unexplained``); :class:`~rodlab.core.errors.RodlabError` listing them otherwise."""
    kinds = effect_id_kinds()
    if isinstance(value, kinds):
        return value
    for kind in kinds:
        try:
            return kind(str(value).strip().lower())
        except ValueError:
            continue
    choices = [m.value for kind in kinds for m in kind]
    raise RodlabError(f"unknown effect {value!r}; expected one of {choices}." + did_you_mean(str(value), choices))
