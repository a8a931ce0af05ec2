"""The joint-calibrated frame of a design family: one solid FEA run calibrates the frame's joints, which then
carry over to every L1 x L2 member (docs/fea.md). Shared by ``rodlab sweep --calibrate`` and ``rodlab study``."""
from __future__ import annotations

import hashlib
import json
import logging
from importlib.util import find_spec
from pathlib import Path

from rodlab.core.design import RodDesign
from rodlab.core.design_io import design_to_dict
from rodlab.core.errors import RodlabError
from rodlab.fea import run_solid
from rodlab.fea.family import calibration_member
from rodlab.fea.joints_io import read_joints, write_joints

from ..solid_mesher import solid_mesher

__all__ = ["solid_family_calibration", "cad_available", "family_joints"]

log = logging.getLogger(__name__)


def cad_available(mesh_only: bool = False) -> bool:
    """True when the cad extra (build123d and gmsh; gmsh alone with ``mesh_only``: it builds the parts it
    meshes itself) is installed: found, not imported (build123d's import alone takes ~2 s)."""
    return find_spec("gmsh") is not None and (mesh_only or find_spec("build123d") is not None)


def solid_family_calibration(base: RodDesign, L1s=(), L2s=()):
    """A :class:`rodlab.fea.joints.JointCalibration` of ``base``'s family from one solid run of its calibration
    member (``base``, or the grid's nearest design whose free tubes are long enough); needs the cad extra."""
    return _solve(calibration_member(base, L1s, L2s), base)


def _solve(member: RodDesign, base: RodDesign):
    log.info("joint calibration of %s's family on a solid run of %s", base.name, member.name)
    return run_solid(member, solid_mesher(member), error_estimate=False, joints=True).joints


def _family_joints(base, L1s, L2s, cache: Path):
    """The family's joint calibration, solved once and kept in ``cache/joints`` (keyed by the solid-run
    design's identity), so a re-run or a resumed study does not solve again."""
    member = calibration_member(base, L1s, L2s)
    key = hashlib.sha256(json.dumps(design_to_dict(member), sort_keys=True, default=str).encode()).hexdigest()[:20]
    path = cache / "joints" / f"{key}.joints.json"
    if path.exists():
        try:
            return read_joints(path)
        except RodlabError:
            pass
    jc = _solve(member, base)
    write_joints(path, jc)
    return jc


def _family_key(design: RodDesign) -> str:
    """What a family's members share: everything but the name, L1 and L2 (as :meth:`~fea.joints.JointFit.
    check_member` asks); a rod as built (other moduli under the same material's name, a paper trial) is a family
    of its own."""
    data = {k: v for k, v in design_to_dict(design).items() if k not in ("format", "name", "L1_mm", "L2_mm")}
    return json.dumps(data, sort_keys=True, default=str)


def family_joints(cands, grid: bool, use_solid: bool, cache: Path) -> tuple[dict, str]:
    """{candidate label: JointCalibration} per design family (the designs that differ only in L1 / L2; one solid
    run each, kept in ``cache``), or {} when ``use_solid`` is off or the cad extra is missing; and a note on the
    compliance model used. ``grid``: the candidates form an L1 x L2 grid (the family's calibration member may
    then be another grid design whose free tubes are long enough)."""
    if not use_solid:
        return {}, "frame with its global calibration (--no-calibrate)"
    if not cad_available(mesh_only=True):
        return {}, "frame with its global calibration (the cad extra for the solid run is not installed)"
    families: dict = {}
    for c in cands:
        if c.design is not None:
            families.setdefault(_family_key(c.design), []).append(c)
    out, failed = {}, []
    for members in families.values():
        base = members[0].design
        L1s = sorted({c.L1_mm for c in members}) if grid else []
        L2s = sorted({c.L2_mm for c in members}) if grid else []
        try:
            jc = _family_joints(base, L1s, L2s, cache)
        except RodlabError as e:             # one family's solid run (too large a mesh, ...) does not stop the rest
            log.warning("%s: its family's solid run failed (%s); its designs use the frame's global calibration",
                        base.name, e)
            failed.append(base.name)
            continue
        for c in members:
            out[c.label] = jc
    note = f"frame joint-calibrated on {len(families) - len(failed)} solid FEA run(s), one per design family"
    if failed:
        note += f"; the global frame for the family of {', '.join(failed)} (its solid run failed: see the warning)"
    return out, note
