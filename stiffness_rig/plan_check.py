"""Checks of a load schedule against the rod it loads: a carbon rod beyond the paper's linear range.

The paper (Section 5.1) reports that a carbon-fibre rod deforms linearly only under small loads, below 15 N;
above it creep and other nonlinear deformation grow, so a compliance fitted over heavier holds is not the one
the calibration's light contact forces see. Each mass whose weight exceeds the limit is named with its holds.
"""
from __future__ import annotations

from rodlab.core.units import G0

__all__ = ["CARBON_LINEAR_LIMIT_N", "PAPER_MASSES_KG", "default_masses", "is_carbon", "linear_range_warnings"]

#: the paper's linear range of a carbon-fibre rod [N]
CARBON_LINEAR_LIMIT_N = 15.0

#: the paper's loading masses (Section 5.1) [kg]
PAPER_MASSES_KG = (0.5, 1.0, 1.5, 2.0)


def is_carbon(design) -> bool:
    """Whether the rod's tubes (pipe I or pipe II) are carbon fibre: a material ``cfrp*``, or a laminate of the
    user's (a transverse or shear modulus of its own, as docs/formats.md defines a laminate; a trial's ``cf_t59``
    had been loaded with 2 kg unwarned)."""
    return any(t.material.name.startswith("cfrp") or not t.material.is_isotropic for t in (design.pipe_I, design.pipe_II))


def default_masses(design=None) -> tuple:
    """The masses [kg] of a load plan nobody chose: the paper's (:data:`PAPER_MASSES_KG`); on a carbon rod only
    those within the linear range the paper reports for it (1.5 kg = 14.7 N), so the default plan is one the rod
    takes linearly. ``design`` None (the rod is not known): the paper's."""
    if design is None or not is_carbon(design):
        return PAPER_MASSES_KG
    return tuple(m for m in PAPER_MASSES_KG if m * G0 <= CARBON_LINEAR_LIMIT_N)


def linear_range_warnings(schedule, design, limit_N: float = CARBON_LINEAR_LIMIT_N) -> list[str]:
    """One warning per mass of ``schedule`` (a :class:`~.model.LoadSchedule`) whose weight exceeds ``limit_N``
    on a carbon rod, naming its holds (K/N as ``rig acquire`` counts them); none for a metal rod."""
    if not is_carbon(design):
        return []
    holds = schedule.holds()
    heavy: dict[float, list[str]] = {}
    for k, (axis, rep, phase, mass) in enumerate(holds, start=1):
        if mass * G0 > limit_N:
            heavy.setdefault(mass, []).append(f"{k}/{len(holds)} ({axis.value}, {phase}, repeat {rep})")
    out = []
    for mass, names in sorted(heavy.items()):
        shown = ", ".join(names[:4]) + (f" and {len(names) - 4} more" if len(names) > 4 else "")
        out.append(f"{mass:g} kg loads the carbon rod {design.name} with {mass * G0:.1f} N, beyond the {limit_N:g} N "
                   f"the paper reports as its linear range (creep and nonlinear deformation grow above it): hold "
                   f"{shown}; keep the masses <= {limit_N / G0:.2f} kg or fit only the lighter holds")
    return out
