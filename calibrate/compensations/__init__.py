"""Compensations: one module per effect of the rod that identification removes from the measured ball centres and
the simulator adds to its readings (:class:`~.base.Compensation`: ball-centre offsets in {W} from the current
model); one registry, :data:`COMPENSATIONS`, keyed by name.

Adding a compensation is a module in this package with a :class:`~.base.Compensation` subclass (``name``,
``summary``, ``needs``, ``option`` and ``offsets``) and a test: :func:`discover` (run on import) finds every
module of the package. ``identify(..., compensations=[...])``,
``simulate_campaign(..., compensations=[...])``, the help of ``rodlab calibrate`` and the table of
docs/calibrate.md take it from here.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.registry import package_classes, sorted_by_id

from .base import Compensation, Poses
from .rod_deflection import RodDeflection, deflection_basis, deflection_offsets, flange_loads
from .thermal_growth import ThermalGrowth, tool_axes_W

__all__ = ["COMPENSATIONS", "Compensation", "Poses", "RodDeflection", "ThermalGrowth", "deflection_offsets",
           "deflection_basis", "flange_loads", "tool_axes_W", "total_offsets", "compensation_label",
           "compensations_markdown", "compensations_help", "discover"]

#: every compensation class, by name (in the order of the name; a calibration sums the offsets of the ones it is
#: given in the order given); filled by :func:`discover`
COMPENSATIONS: dict[str, type[Compensation]] = {}


def discover() -> dict[str, type[Compensation]]:
    """Find the compensations: every :class:`Compensation` subclass with a ``name`` that the modules of this
    package define (a folder added to its ``__path__`` too); refill :data:`COMPENSATIONS` in place and return it.
    Run on import; run it again after changing the package's ``__path__``."""
    found = sorted_by_id(package_classes(__name__, Compensation, "name"), "name", "compensation")
    COMPENSATIONS.clear()
    COMPENSATIONS.update({c.name: c for c in found})
    return COMPENSATIONS


discover()


def total_offsets(compensations, robot, params, at) -> np.ndarray:
    """The sum of the ``compensations``' ball-centre offsets in {W} [mm], shape=(N, 3), at the points ``at``
    (zeros without any)."""
    out = np.zeros((np.atleast_2d(at.q_rad).shape[0], 3))
    for c in compensations:
        out = out + c.offsets(robot, params, at)
    return out


def compensation_label(compensations) -> str:
    """What a result calls its compensation: the labels joined with ``+`` (e.g. ``fea+thermal``; ``none+thermal``
    when the rod's deflection is left out), ``none`` without any."""
    return "+".join(c.label for c in compensations) or "none"


def compensations_markdown() -> str:
    """The registry as the Markdown table of docs/calibrate.md (``scripts/gen_cli_docs.py``)."""
    rows = ["| compensation | what it removes | needs | `rodlab calibrate` |", "|---|---|---|---|"]
    rows += [f"| `{name}` | {c.summary} | {c.needs} | {c.option} |" for name, c in COMPENSATIONS.items()]
    return "\n".join(rows)


def compensations_help() -> str:
    """One line per compensation for the command-line help."""
    return "; ".join(f"{name}: {c.option.replace('`', '')}" for name, c in COMPENSATIONS.items())

