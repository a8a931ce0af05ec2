"""What an r_rod (Eq. 21: measured / simulated) says beyond its value: a units slip or another rod's file where no
rod has it against its own simulation, and a remark where it lies outside the paper's measured rods."""
from __future__ import annotations

from rodlab.core.units import PAPER_R_ROD

__all__ = ["PLAUSIBLE_R_ROD", "r_rod_caution", "r_rod_note"]

#: r_rod a rod can have against its own simulation (the paper's: 1.01-2.30); beyond it, a units slip is likelier
PLAUSIBLE_R_ROD = (0.1, 10.0)


def r_rod_caution(r_rod: float, recording_rod: str | None, sim_rod: str) -> str | None:
    """What to check when ``r_rod`` is beyond any rod against its own simulation (:data:`PLAUSIBLE_R_ROD`): a
    mass in g, readings in um, another rod's file; None when it is plausible."""
    lo, hi = PLAUSIBLE_R_ROD
    if lo <= r_rod <= hi:
        return None
    said = f" (the recording says rod {recording_rod!r})" if recording_rod else ""
    return (f"r_rod = {r_rod:.3g}: the rod is {r_rod:.3g} x as compliant as the simulation of rod {sim_rod!r}, beyond "
            f"any rod ({lo:g}-{hi:g}; the paper's 1.01-2.30). Check the recording's units (mass_kg in kg, not g; "
            f"disp_*_mm in mm, not um) and that the simulation is this rod's{said}")


def r_rod_note(r_rod: float, method: str) -> str | None:
    """What an r_rod within :data:`PLAUSIBLE_R_ROD` but outside the paper's measured rods (1.01-2.30,
    :data:`~rodlab.core.units.PAPER_R_ROD`) says, against a simulation of ``method``; None within them (a paper
    trial: r_rod 0.80 and 3.50 had passed without a remark)."""
    lo, hi = PAPER_R_ROD
    if lo - 0.05 <= r_rod <= hi + 0.05:
        return None
    if r_rod < lo:
        stiffer = (" (the closed form is already 6-17 % stiffer than the solid FEA: a rod stiffer than it is rarer "
                   "still)" if method == "calc" else "")
        return (f"r_rod {r_rod:.2f}: the rod is stiffer than its simulation{stiffer}, and no rod the paper measured is "
                f"(1.01-2.30): check the simulation's materials and sizes against the rod, the masses hung and the "
                f"gauges' gain before using the file")
    return (f"r_rod {r_rod:.2f}: beyond the paper's softest rod (carbon 3#, 2.30): bonds, clamps or creep may carry "
            f"part of it (`rodlab diagnose --rig` locates a joint); the study's rod slip was fitted within 1.01-2.30")
