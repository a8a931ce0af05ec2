"""One solid run and what is made from it: the compliance, the frame's joint fit, the deformed-shape
figure. ``rodlab fea --model solid``, the demo and the design study's family calibration all call
:func:`run_solid` (they only parse, call and print)."""
from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

from rodlab.core.compliance import RodCompliance
from rodlab.core.design import RodDesign
from rodlab.core.enums import ErrorEstimate

from .compute import Mesher, solid_compliance
from .joints import JointFit, fit_joints
from .plan_cache import PlanCache
from .solid import SolidResult
from .plot import render_deformed

__all__ = ["SolidRun", "run_solid"]

log = logging.getLogger(__name__)


@dataclass
class SolidRun:
    """A solid FEA run of one design.

    compliance : C_F [mm/N] and C_g [mm/g0] in {T} (method ``fea``); result : the solid solution (mesh,
    displacements of the unit load cases when kept); joints : the frame's joint fit on this run, or
    None when not asked; figures : the figures written, in order
    """

    compliance: RodCompliance
    result: SolidResult
    joints: JointFit | None = None
    figures: list[Path] = field(default_factory=list)


def run_solid(design: RodDesign, mesher: Mesher, *, size_mm: float | None = None,
              error_estimate: ErrorEstimate | str | bool = ErrorEstimate.RECOVERY,
              symmetry: bool = True, joints: bool = False, deformed_png: str | Path | None = None,
              backend: str | None = None, keep_displacements: bool = False, plans: PlanCache | None = None) -> SolidRun:
    """Solve ``design`` with the solid model (``mesher``: :func:`rodlab.geometry.mesh_rod`; ``error_estimate`` as
    :func:`~fea.compute.solid_compliance`); with ``joints``
    calibrate the frame's joints on the run (:func:`~rodlab.fea.joints.fit_joints`); with
    ``deformed_png`` draw the self-weight deformation (gravity along -z_T, as on a vertical flange); with
    ``keep_displacements`` the result keeps the load cases' displacements (for :mod:`fea.fields`); ``plans`` keeps
    the mesh's assembly plan between runs (:class:`~fea.plan_cache.PlanCache`)."""
    comp, res = solid_compliance(design, mesher, size_mm=size_mm, error_estimate=error_estimate,
                                 keep_displacements=keep_displacements or bool(deformed_png) or joints, symmetry=symmetry,
                                 tip_moments=joints, backend=backend, plans=plans)
    run = SolidRun(comp, res)
    if deformed_png:
        run.figures.append(_deformed_figure(design, res, deformed_png))
    if joints:
        run.joints = fit_joints(design, res)
        log.info("joint calibration of %s: span fit residual %.2f %%", design.name, 100 * run.joints.span_residual)
    return run


def _deformed_figure(design: RodDesign, res: SolidResult, path) -> Path:
    U = res.displacements.copy()
    U[:, 5] *= -1.0                                     # gravity along -z_T, as on a vertical flange
    return render_deformed(res.rod_mesh, U, path, case=5, title=f"rod {design.name}: self-weight, gravity along -z_T",
                           load_label="self-weight, 1 g0 along -z_T")
