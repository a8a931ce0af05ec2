"""The corrected compliance: the simulated model with the structural physics the diagnosis found."""
from __future__ import annotations

import numpy as np

from rodlab.stiffness_rig.completion import complete_c_f
from rodlab.stiffness_rig.effects import RIG_EFFECTS, RigEffect, held_creep_share
from rodlab.stiffness_rig.effects.springs import joint_places

from ...core.compliance import RodCompliance
from ...core.enums import Method

__all__ = ["corrected_compliance"]


def corrected_compliance(sim: RodCompliance, diag, model, measured_axes=(0, 1, 2), source: str = "",
                         design=None) -> RodCompliance:
    """``sim`` plus the fitted structural terms (compliance scale, torsion, joint springs); C_g scaled by the
    change of c22 + c33 (as Eq. 22 does for the measured file). Where the linear compliance was fitted freely
    (the simulation not taken to be exact), that fit is the corrected C_F. Rig effects (friction, tare, drift, crosstalk)
    belong to the rig, not the rod, and are left out; a creep's share that a hold of the recording shows is kept
    (:func:`_with_held_creep`). ``measured_axes``: the load axes the recording
    ``source`` loaded (0-2 for x-z); where the linear compliance was fitted freely, the entries it could not fit
    (an axis not loaded) are the simulation with the structural findings applied (:func:`_with_findings`: a
    compliant flange joint found from the loaded axes adds to c11 too; ``design`` places the joints); a diagonal
    entry is then raised where the others need it to be a compliance (:func:`~stiffness_rig.completion.complete_c_f`,
    noted in the provenance)."""
    notes = []
    if model.linear is None:
        C = sim.C_F.copy()
        for term, v in model.term_values():
            for val, dC in zip(v, term.dC or ()):
                C = C + val * dC
    else:                                   # the free fit holds every effect on the entries it fits
        C, grouped = _with_findings(sim, diag, design)
        found = C.copy()
        for m, n in model.linear.entries:
            C[m, n] = C[n, m] = model.linear.C_F[m, n]
        C, scaled = _unloaded_scaled(C, found, model.linear.entries)
        notes += _predicted_note(C, sim, diag, measured_axes) + _group_notes(grouped, measured_axes) + scaled
    C, held = _with_held_creep(0.5 * (C + C.T), diag)
    notes += held
    r = float((C[1, 1] + C[2, 2]) / (sim.C_F[1, 1] + sim.C_F[2, 2]))    # of the model, before any completion
    loaded = np.zeros((3, 3), dtype=bool)
    loaded[:, list(measured_axes)] = True
    C, raised = complete_c_f(np.where(loaded | loaded.T, C, np.nan), C, source, "the corrected model's")
    notes += raised
    return RodCompliance(sim.rod, Method.MEAS, C, r * sim.C_g, sim.mass_kg, sim.com_T_mm, sim.tool_mm,
                         r * sim.r_rod, {"generator": "rodlab diagnose --export", "simulated": sim.provenance,
                                         "findings": [f.to_dict() for f in diag.findings], "warnings": notes})


def _unloaded_scaled(C: np.ndarray, found: np.ndarray, entries) -> tuple[np.ndarray, list[str]]:
    """The entries no series loaded, from the simulation with the findings (``found``) times what the measured
    on-axis entries say is left beyond the findings (their sum over the same sum of ``found``), as `rig fit`
    completes its file with r_rod (an independent recordings trial: without an x series, c11 had stayed the
    simulation's while C_g took r_rod 1.15: 15 % off the truth where `rig fit` was 3 %)."""
    diag = [k for k in (0, 1, 2) if (k, k) in set(entries)]
    if not diag or len(diag) == 3:
        return C, []
    k = float(sum(C[i, i] for i in diag) / sum(found[i, i] for i in diag))
    measured = np.zeros((3, 3), dtype=bool)
    for m, n in entries:
        measured[m, n] = measured[n, m] = True
    out = np.where(measured, C, k * found)
    return out, [f"entries no series loaded ({', '.join(f'c{m + 1}{n + 1}' for m, n in zip(*np.nonzero(np.triu(~measured))))}) "
                 f"are the simulation with the findings times {k:.4g}, what the measured diagonal says is left beyond "
                 "them (as `rig fit` completes its file with r_rod)"]


def _with_findings(sim: RodCompliance, diag, design=None) -> tuple[np.ndarray, list]:
    """The simulated C_F [mm/N] with each structural rig finding's fitted parameters put through its effect's
    forward model (:meth:`~stiffness_rig.effects.base.RigEffectModel.compliance`, the joints placed on ``design``
    or guessed from the tool vector), and the findings at a group of places the recording could not tell apart
    (``pipe_II|ring_1``): each is put at the first place, where the diagnosis fitted it (a technician trial: the
    export had failed on the group's name)."""
    C = sim.C_F.copy()
    places = joint_places(sim.tool_mm, design)
    grouped = []
    for f in diag.findings:
        if not isinstance(f.effect, RigEffect) or not RIG_EFFECTS[f.effect].structural:
            continue
        params = dict(f.parameters)
        if f.location:
            params["location"] = f.location.split("|")[0]
            if "|" in f.location:
                grouped.append(f)
        C = RIG_EFFECTS[f.effect].compliance(C, params, places)
    return C, grouped


def _group_notes(grouped: list, measured_axes) -> list[str]:
    """Which place the file takes for a finding at a group of places, and what that decides: the entries of the
    axes the recording did not load."""
    unloaded = [i for i in range(3) if i not in set(measured_axes)]
    out = []
    for f in grouped:
        first, *others = f.location.split("|")
        decides = (f"; its entries along {', '.join('xyz'[i] for i in unloaded)} (not loaded) depend on the place: load "
                   f"along {', '.join('xyz'[i] for i in unloaded)} to tell them apart") if unloaded else ""
        out.append(f"{f.effect} at {f.location}: the recording cannot tell these places apart; the file puts it at "
                   f"{first}, where the diagnosis fitted it (not at {', '.join(others)}){decides}")
    return out


def _predicted_note(C: np.ndarray, sim: RodCompliance, diag, measured_axes) -> list[str]:
    """What the corrected file holds on the diagonal of the axes the recording did not load: a prediction of the
    simulation with the structural findings (named), not a measurement."""
    unloaded = [i for i in range(3) if i not in set(measured_axes)]
    if not unloaded:
        return []
    found = [f"{f.effect}" + (f" at {f.location}" if f.location else "") for f in diag.findings
             if isinstance(f.effect, RigEffect) and RIG_EFFECTS[f.effect].structural]
    what = (f"the simulation with {' and '.join(found)} as found" if found else "the simulation") + (
        ", scaled as the measured entries say (below)")
    values = ", ".join(f"c_{'xyz'[i]}{'xyz'[i]} {C[i, i]:.4g} mm/N (simulated {sim.C_F[i, i]:.4g})" for i in unloaded)
    axes = ", ".join("xyz"[i] for i in unloaded)
    return [f"no load along {axes}: {values} from {what}, a prediction, not a measurement; record a load along "
            f"{axes} to measure it"]


def _with_held_creep(C: np.ndarray, diag) -> tuple[np.ndarray, list[str]]:
    """``C`` with the creep that is complete within a hold of the recording (its median length:
    :func:`~stiffness_rig.effects.creep.held_creep_share`): no reading, on the rig or in a calibration, sees the
    load's first instant, so a fast creep is the rod's compliance (as the diagnosis reads a creep settled before a
    hold's first reading); a slower one stays out, the file the elastic compliance, and a note says how much more
    a load held for long deflects the rod."""
    hold_s = float(diag.extra.get("hold_median_s") or 0.0)
    creep = [f for f in diag.findings if f.effect == "creep"]
    if not creep or not hold_s > 0:
        return C, []
    shares = [held_creep_share(f.parameters, hold_s) for f in creep]
    fast, slow = sum(a for a, _ in shares), sum(b for _, b in shares)
    notes = []
    if fast:
        notes.append(f"the creep found that is complete within a hold of the recording ({hold_s:.3g} s) is in the "
                     f"file: x{1.0 + fast:.4f} on the elastic compliance")
    if slow:
        with_fast = " with the fast creep" if fast else ""
        notes.append(f"the slower creep found is not in the file (the elastic compliance{with_fast}): a load held "
                     f"for long deflects the rod x{(1.0 + fast + slow) / (1.0 + fast):.4f} as much")
    return C * (1.0 + fast), notes
