"""fea: rod compliance C^F and C^g by 3-D solid FEA (scikit-fem), a fast beam-frame model, and design sweeps.

The solid model consumes a :class:`rodlab.core.fem_mesh.RodMesh` (made by ``geometry``), never imports geometry.
"""
from .compute import DEFAULT_GRADING, FeaModel, Mesher, compute_compliance, default_solid_size_mm, solid_compliance
from .errors import FeaError
from .frame import BendFlexibility, asme_bend_flexibility, frame_compliance
from .joints import JointCalibration, JointFit, calibrate_joints, fit_joints, joint_frame_compliance
from .modal import chain_frequencies, frame_frequencies
from .modal_solid import SolidModes, solid_frequencies
from .solid import SolidResult, mirror_displacements, solve_compliance
from .solid_run import SolidRun, run_solid

__all__ = ["FeaModel", "Mesher", "compute_compliance", "solid_compliance", "default_solid_size_mm", "DEFAULT_GRADING",
           "FeaError", "BendFlexibility", "asme_bend_flexibility", "frame_compliance", "SolidResult",
           "solve_compliance", "mirror_displacements", "JointFit", "fit_joints", "JointCalibration", "calibrate_joints",
           "joint_frame_compliance", "frame_frequencies", "chain_frequencies", "SolidModes", "solid_frequencies",
           "SolidRun", "run_solid"]
