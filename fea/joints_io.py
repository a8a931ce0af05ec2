"""Joint-fit files (``*.joints.json``, format ``rodlab.joints/1``): calibrate once, sweep many times.

A joint fit (:class:`fea.joints.JointFit`) costs one solid FEA run; the file keeps it with the
calibrated design (every part and material's numbers, so that a revised built-in material does not change its
meaning) and the frame it corrects, so that ``rodlab sweep --joints FILE`` and ``rodlab fea --model frame
--joints FILE`` reuse it for any member of the family. Layout (docs/formats.md)::

    {"format": "rodlab.joints/1", "design": {rodlab.rod/1 table}, "margins_mm": [pipe I, pipe II],
     "D": 5 x 6 x 6, "dH": 5 x 6 x 3, "section": 2 x 6, "frame_revision": 3, "frame_calibration": {...},
     "asymmetry": ..., "span_residual": ..., "provenance": {...}}
"""
from __future__ import annotations

import json
from dataclasses import asdict, fields
from pathlib import Path

import numpy as np

from rodlab.core.design_io import design_from_dict, design_to_dict
from rodlab.core.errors import FormatError
from rodlab.core.fileio import atomic_write_json, read_text_checked

from .errors import FeaError
from .frame import FRAME_REVISION, FrameCalibration
from .joints import JointFit

__all__ = ["FORMAT_JOINTS", "write_joints", "read_joints"]

FORMAT_JOINTS = "rodlab.joints/1"
_SHAPES = {"margins_mm": (2,), "D": (5, 6, 6), "dH": (5, 6, 3), "section": (2, 6)}


def write_joints(path: str | Path, jc: JointFit, provenance: dict | None = None) -> Path:
    """Write ``jc`` to ``path`` (atomically) with optional ``provenance`` (e.g. the solid run's DOFs)."""
    return atomic_write_json(path, {
        "format": FORMAT_JOINTS, "design": design_to_dict(jc.base), "margins_mm": list(jc.margins_mm),
        "D": jc.D.tolist(), "dH": jc.dH.tolist(), "section": jc.section.tolist(),
        "frame_revision": FRAME_REVISION, "frame_calibration": asdict(jc.calibration),
        "asymmetry": jc.asymmetry, "span_residual": jc.span_residual, "provenance": provenance or {}})


def read_joints(path: str | Path) -> JointFit:
    """Read a ``*.joints.json``; errors name the file and key (:class:`FeaError`)."""
    text = read_text_checked(path, FeaError)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise FeaError(f"not JSON ({e.msg})", path=path, line=e.lineno) from e
    if not isinstance(data, dict) or data.get("format") != FORMAT_JOINTS:
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise FeaError(f"expected format {FORMAT_JOINTS!r}, got {got!r}", path=path, key="format")
    missing = [k for k in ("design", "frame_revision", "frame_calibration", *_SHAPES) if k not in data]
    if missing:
        raise FeaError(f"missing {', '.join(missing)}", path=path, key=missing[0])
    if data["frame_revision"] != FRAME_REVISION:
        raise FeaError(f"calibrated against frame revision {data['frame_revision']!r}, this rodlab has "
                       f"{FRAME_REVISION}: recalibrate (rodlab sweep --calibrate, or rodlab fea --model solid "
                       f"--joints-out)", path=path, key="frame_revision")
    arrays = {}
    for key, shape in _SHAPES.items():
        try:
            a = np.asarray(data[key], dtype=float)
        except (TypeError, ValueError) as e:
            raise FeaError(f"expected numbers, shape {shape}", path=path, key=key) from e
        if a.shape != shape or not np.all(np.isfinite(a)):
            raise FeaError(f"expected finite numbers of shape {shape}, got shape {a.shape}", path=path, key=key)
        arrays[key] = a
    if np.any(arrays["margins_mm"] <= 0):
        raise FeaError(f"margins must be positive [mm], got {arrays['margins_mm'].tolist()}", path=path,
                       key="margins_mm")
    extra = {}
    for key in ("asymmetry", "span_residual"):
        v = data.get(key, 0.0)
        if not isinstance(v, (int, float)) or isinstance(v, bool) or not np.isfinite(v):
            raise FeaError(f"expected a finite number, got {v!r}", path=path, key=key)
        extra[key] = float(v)
    if not isinstance(data["design"], dict):
        raise FeaError("expected the calibrated design as a rodlab.rod/1 table", path=path, key="design")
    try:
        design = design_from_dict(data["design"])
    except FormatError as e:
        raise FeaError(f"the calibrated design: {e}", path=path, key="design") from e
    cal = data["frame_calibration"]
    names = [f.name for f in fields(FrameCalibration)]
    if not isinstance(cal, dict) or set(cal) - set(names):
        raise FeaError(f"expected the frame constants {', '.join(names)}", path=path, key="frame_calibration")
    try:
        return JointFit(design, tuple(float(m) for m in arrays["margins_mm"]), arrays["D"], arrays["dH"],
                                arrays["section"], FrameCalibration(**cal), extra["asymmetry"],
                                extra["span_residual"])
    except (TypeError, ValueError) as e:
        raise FeaError(str(e), path=path, key="frame_calibration") from e
