"""The designs the beam frame is calibrated and validated on, and their stored solid-FEA references.

Versioned data, not code: ``fea/data/reference_designs.json`` (format ``rodlab.reference_designs/1``) holds
the full rods A-Z beside the built-in rod1-rod6, the part probes (rods reduced to one joint: ``holder_*``,
``rings_*``, ``bend_*``), thin-walled bends outside the calibrated range, off-grid members of the paper's
two families, and which of them were fitted (calibration set) and which held out (validation set).
``solid_reference.json`` holds their solid C_F / C_g; ``solid_joint_blind_reference.json`` the random
families drawn blind for the joint fit. ``scripts/calibrate_frame.py`` and
``scripts/frame_random_blind.py`` (re)compute those references; the tests read them through this module.
"""
from __future__ import annotations

import json
from dataclasses import replace
from functools import lru_cache
from pathlib import Path

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.design_io import design_from_dict, resolve_design
from rodlab.core.enums import Part

from .frame import frame_errors
from .joints import joint_frame_compliance, joints_from_motions

__all__ = ["DATA", "reference_sets", "reference_design", "reference_spec", "spec_design", "solid_references",
           "random_references", "joint_blind_references", "random_global_errors", "family_errors"]

DATA = Path(__file__).resolve().parent / "data"


@lru_cache(maxsize=1)
def _catalogue() -> dict:
    data = json.loads((DATA / "reference_designs.json").read_text())
    if data.get("format") != "rodlab.reference_designs/1":
        raise ValueError(f"{DATA / 'reference_designs.json'}: expected format rodlab.reference_designs/1")
    return data


def reference_sets() -> dict[str, list[str]]:
    """{"calibration", "validation", "probes", "thin", "families": {base: [members]}} of design names."""
    c = _catalogue()
    return {"calibration": list(c["sets"]["calibration"]), "validation": list(c["sets"]["validation"]),
            "probes": list(c["probes"]), "thin": list(c["thin_probes"]),
            "families": {k: list(v) for k, v in c["families"].items()}}


def spec_design(name: str, spec: dict) -> RodDesign:
    """A design from a rodlab.rod/1 table without its format and name keys."""
    return design_from_dict(dict({"format": "rodlab.rod/1", "name": name}, **spec))


def reference_design(name: str) -> RodDesign:
    """A reference design by name: a full rod (A-Z), a probe, a thin probe, an off-grid family member
    (``rod1_L1_200_L2_600``: rod1's parts at other L1 / L2) or a built-in rod."""
    c = _catalogue()
    if name in c["family_off_grid"]:
        f = c["family_off_grid"][name]
        return replace(reference_design(f["base"]), L1_mm=f["L1_mm"], L2_mm=f["L2_mm"], name=name)
    spec = c["specs"].get(name) or c["probes"].get(name) or c["thin_probes"].get(name)
    if spec is not None:
        return spec_design(name, spec)
    return resolve_design(name)


def reference_spec(name: str) -> dict:
    """The rodlab.rod/1 table (without format and name) of a full rod, probe or thin probe."""
    c = _catalogue()
    spec = c["specs"].get(name) or c["probes"].get(name) or c["thin_probes"].get(name)
    if spec is None:
        raise KeyError(f"{name!r} is not a stored reference spec")
    return json.loads(json.dumps(spec))


def solid_references() -> dict:
    """{name: {"C_F", "C_g", ...}} of the solid model at the default mesh."""
    return json.loads((DATA / "solid_reference.json").read_text())


def random_references() -> dict:
    """The random designs inside the calibrated range, with their solid C_F / C_g, and the family variants and
    base section motions of the 10 worst (``scripts/frame_random_blind.py``)."""
    return json.loads((DATA / "solid_random_reference.json").read_text())


def random_global_errors(refs: dict) -> dict:
    """Largest relative error [-] of the globally calibrated frame on each random (non-variant) design."""
    return {n: float(np.abs(frame_errors(spec_design(n, r["spec"]), r["C_F"], r["C_g"])).max())
            for n, r in refs["designs"].items() if "_v" not in n}


def joint_blind_references() -> dict:
    """The blind random families of the joint fit: designs with their solid C_F / C_g, and the bases'
    section motions."""
    return json.loads((DATA / "solid_joint_blind_reference.json").read_text())


def family_errors(refs: dict) -> dict:
    """Per family: max error [-] on its two variants of the frame joint-fitted on the base's stored solid
    measurements (what ``rodlab sweep --calibrate`` does, :mod:`fea.joints`), and of the global calibration."""
    ds = refs.get("designs", {})
    out = {}
    for base, j in refs.get("joints", {}).items():
        b = spec_design(base, ds[base]["spec"])
        jc = joints_from_motions(b, np.array(j["section_motion"]), np.array(j["tip_motion"]),
                                 dict(zip((Part.PIPE_I, Part.PIPE_II), j["margins_mm"])))
        e_joint, e_glob = [], []
        for v in (f"{base}_v0", f"{base}_v1"):
            dv = spec_design(v, ds[v]["spec"])
            ref = (np.asarray(ds[v]["C_F"]), np.asarray(ds[v]["C_g"]))
            errs = []
            for mine, r in zip(joint_frame_compliance(dv, jc), ref):
                big = np.abs(r) > 0.02 * np.abs(r).max()
                errs.append(np.abs(mine[big] / r[big] - 1).max())
            e_joint.append(float(max(errs)))
            e_glob.append(float(np.abs(frame_errors(dv, *ref)).max()))
        out[base] = {"joints": max(e_joint), "global": max(e_glob)}
    return out
