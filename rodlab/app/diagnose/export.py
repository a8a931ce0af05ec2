"""The corrected compliance: the simulated model with the structural physics the diagnosis found."""
from __future__ import annotations

import numpy as np

from rodlab.stiffness_rig.completion import complete_c_f

from ...core.compliance import RodCompliance
from ...core.enums import Method

__all__ = ["corrected_compliance"]


def corrected_compliance(sim: RodCompliance, diag, model, measured_axes=(0, 1, 2), source: str = "") -> RodCompliance:
    """``sim`` plus the fitted structural terms (compliance scale, torsion, joint springs); C_g scaled by the
    change of c22 + c33 (as Eq. 22 does for the measured file). Where the linear compliance was fitted freely
    (the simulation not taken to be exact), that fit is the corrected C_F. Rig effects (friction, tare, drift, crosstalk,
    creep) belong to the rig, not the rod, and are left out. ``measured_axes``: the load axes the recording
    ``source`` loaded (0-2 for x-z); a diagonal entry of an axis it did not load is raised where the others need
    it to be a compliance (:func:`~stiffness_rig.completion.complete_c_f`, noted in the provenance)."""
    C = sim.C_F.copy() if model.linear is None else model.linear.C_F.copy()
    for term, v in model.term_values():
        if term.dC:
            for val, dC in zip(v, term.dC):
                C = C + val * dC
    C = 0.5 * (C + C.T)
    r = float((C[1, 1] + C[2, 2]) / (sim.C_F[1, 1] + sim.C_F[2, 2]))    # of the model, before any completion
    loaded = np.zeros((3, 3), dtype=bool)
    loaded[:, list(measured_axes)] = True
    C, notes = complete_c_f(np.where(loaded | loaded.T, C, np.nan), C, source, "the corrected model's")
    return RodCompliance(sim.rod, Method.MEAS, C, r * sim.C_g, sim.mass_kg, sim.com_T_mm, sim.tool_mm,
                         r * sim.r_rod, {"generator": "rodlab diagnose --export", "simulated": sim.provenance,
                                         "findings": [f.to_dict() for f in diag.findings], "warnings": notes})
