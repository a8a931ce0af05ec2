"""fea: rod compliance C^F and C^g by 3-D solid FEA (scikit-fem), a fast beam-frame model, and design sweeps.

The solid model consumes a :class:`rodlab.core.fem_mesh.RodMesh` (made by ``geometry``), never imports geometry.

The names below load their module on first use (PEP 562), so that the frame model (``rodlab.fea.frame``: numpy
and the core only) does not bring scikit-fem and scipy.sparse along (~0.1 s of ``rodlab diagnose --rig``).
"""
from __future__ import annotations

from rodlab.core.lazy import lazy_exports

#: each public name and the module it comes from
_EXPORTS = {
    "FeaModel": "compute", "Mesher": "compute", "compute_compliance": "compute", "solid_compliance": "compute",
    "default_solid_size_mm": "compute", "DEFAULT_GRADING": "compute",
    "FeaError": "errors",
    "BendFlexibility": "frame", "asme_bend_flexibility": "frame", "frame_compliance": "frame",
    "SolidResult": "solid", "solve_compliance": "solid", "mirror_displacements": "solid",
    "JointFit": "joints", "fit_joints": "joints", "JointCalibration": "joints", "calibrate_joints": "joints",
    "joint_frame_compliance": "joints",
    "frame_frequencies": "modal", "chain_frequencies": "modal",
    "SolidModes": "modal_solid", "solid_frequencies": "modal_solid",
    "SolidRun": "solid_run", "run_solid": "solid_run",
    "PlanCache": "plan_cache",
    "closed_form_notes": "closed_form_check",
}

__all__ = list(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
