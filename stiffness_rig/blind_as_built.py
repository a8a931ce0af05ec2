"""Blind rig cases with model-form error: the recording comes from the rod as built, not from the simulation the
diagnosis is given (never from diagnosis code; used by ``benchmarks/diagnose_blind_as_built.py`` and the tests).

The caller supplies the rod as built (``as_built(rng) -> (C_F [mm/N], {key: drawn value})``: the design's
tolerances drawn and simulated by another method than the diagnosis gets); this module adds the case's physics
(``[as_built]`` of ``stiffness_rig/blind_cases.toml``): nothing, one rig effect that no linear compliance
produces (sized SNR 3-60 as the standard batches), a compliant joint well beyond tolerance, a uniform softening
beyond the material's spread, a pair, or an effect outside the library (honest answer ``unexplained``).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from .blind import BlindCase, out_of_library, peak_change, scaled_effects, standard_schedule, unit_effect, blind_definitions
from .effects import joint_places, spring_compliance
from .model import RigModel
from .simulate import simulate_recording

__all__ = ["generate_as_built_cases"]


def _kind(u: float) -> str:
    mix = blind_definitions()["as_built"]
    for kind in ("null", "effect", "joint", "scale", "pair"):
        if u < mix[kind]:
            return kind
    return "oolib"


def _big_joint(rng, C: np.ndarray, places: dict) -> tuple[dict, dict]:
    """A joint whose bending spring raises its largest-affected C_F entry by the drawn share (beyond tolerance)."""
    d = blind_definitions()
    loc = str(rng.choice(d["draws"]["joint_places"]))
    pt, ax = places[loc]
    unit = spring_compliance(np.asarray(pt, float), np.asarray(ax, float), 1e-3, 0.0)   # s_bend 1 rad/(N m)
    rel = np.abs(unit) / np.maximum(np.abs(C), 1e-300)
    i = np.unravel_index(np.argmax(np.where(np.abs(C) > 1e-6 * np.abs(C).max(), rel, 0)), C.shape)
    share = float(rng.uniform(*d["as_built"]["joint_entry_change"]))
    s_bend = share / rel[i]                                                           # rad/(N m)
    params = {"location": loc, "point_T_mm": list(pt), "axis": list(ax), "s_bend_rad_per_Nm": s_bend,
              "s_torsion_rad_per_Nm": 0.0}
    return {"joint_compliance": params}, {"effect": "joint_compliance", "location": loc, "parameters": params,
                                          "entry_change": share}


def generate_as_built_cases(out_dir, as_built, design, n: int = 40, seed: int = 3000) -> list[BlindCase]:
    """``n`` cases of the rod as built (``as_built(rng)``) for ``design``; truth beside each recording."""
    rng = np.random.default_rng(seed)
    d = blind_definitions()
    places = joint_places(design.tool_mm, design)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = []
    for i in range(n):
        kind = _kind(rng.random())
        noise = float(rng.choice(d["draws"]["noise_mm"]))
        proto = standard_schedule(rng)
        C, drawn = as_built(rng)
        effects, truth = _case_physics(kind, rng, C, places, proto, noise)
        model = RigModel(C, effects, noise_mm=noise, resolution_mm=0.001 if noise >= 0.0006 else 0.0001,
                         seed=int(rng.integers(1 << 30)), places=places,
                         temp_amplitude_K=float(rng.uniform(*d["draws"]["temp_amplitude_K"])))
        path = out / f"case{i:03d}.rig.csv"
        simulate_recording(model, proto, path, rod=design.name)
        expected = "consistent" if kind == "null" else "unexplained" if kind == "oolib" else "explained"
        outside = out_of_library(path, rng, noise) if kind == "oolib" else None
        info = {"kind": kind, "effects": truth, "expected_verdict": expected, "noise_mm": noise, "outside": outside,
                "as_built": drawn, "protocol": {"axes": list(proto.axes), "repeats": proto.repeats,
                                                "masses": list(proto.masses), "hold_s": proto.hold_s}}
        (out / f"case{i:03d}.truth.json").write_text(json.dumps(info, indent=1))
        cases.append(BlindCase(path, info))
    return cases


def _case_physics(kind: str, rng, C: np.ndarray, places: dict, proto, noise: float) -> tuple[dict, list]:
    """(effects for the rig model, truth list) of one case."""
    d = blind_definitions()["as_built"]
    effects, truth = {}, []
    if kind in ("effect", "pair"):
        name = str(rng.choice(d["effects"]))
        unit, loc, keys = unit_effect(name, rng, places)
        snr = float(np.exp(rng.uniform(*np.log(blind_definitions()["draws"]["snr"]))))
        scaled = scaled_effects(unit, keys, snr * noise / peak_change(C, unit, proto))
        effects.update(scaled)
        truth.append({"effect": name, "location": loc, "snr": snr, "parameters": scaled[name]})
    if kind in ("joint", "pair"):
        eff, t = _big_joint(rng, C, places)
        effects.update(eff)
        truth.append(t)
    if kind == "scale":
        r = float(rng.uniform(*d["scale_r"]))
        effects["compliance_scale"] = {"r": r}
        truth.append({"effect": "compliance_scale", "location": None, "parameters": {"r": r}})
    return effects, truth
