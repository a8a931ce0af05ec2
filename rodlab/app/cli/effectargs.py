"""``--effect NAME[:key=value,...]`` options: parsed and checked against an effect registry (rig or campaign),
and the help text listing that registry's effects with their parameters and units."""
from __future__ import annotations

from ...core.errors import RodlabError

__all__ = ["parse_effect_specs", "effects_help"]


def parse_effect_specs(specs: list[str], lookup) -> list[tuple[str, dict]]:
    """``NAME[:key=value,...]`` -> [(name, given parameters)]; names, keys and values checked by the effect
    ``lookup(name)`` returns (its ``complete`` fills in the defaults). Vectors take ``;`` between their numbers
    (``offset_mm=0.1;0;0``)."""
    out = []
    for spec in specs:
        name, _, rest = spec.partition(":")
        try:
            model = lookup(name.strip())
        except RodlabError as e:
            raise RodlabError(f"--effect {spec!r}: {e}") from None
        given = {}
        for kv in filter(None, rest.split(",")):
            k, eq, v = kv.partition("=")
            if not eq:
                raise RodlabError(f"--effect {spec!r}: expected key=value, got {kv!r}; keys of {model.effect}: "
                                  f"{[p.name for p in model.params]}")
            given[k.strip()] = v.strip().replace(";", ",")
        try:
            model.complete(given)
        except RodlabError as e:
            raise RodlabError(f"--effect {spec!r}: {e}") from None
        out.append((str(model.effect), given))
    return out


def effects_help(registry: dict) -> str:
    """One line per effect of ``registry``: its ID, what it models and its parameters with units."""
    lines = []
    for e, m in registry.items():
        keys = ", ".join(f"{p.name} [{p.unit}]" if p.kind != "str" else f"{p.name} ({'|'.join(p.choices)})"
                         for p in m.params)
        lines.append(f"  {e.value}: {m.physics}; {keys}")
    return "\n".join(lines)
