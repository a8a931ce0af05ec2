"""Rod compliance files from the solid FEA, the frame model or the closed form.

``solid`` runs the 3-D model on a graded curved-P2 mesh (reference) of half the rod (it is mirror-symmetric
about its bend plane: two half-size solves, the same answer as the whole mesh) with an estimate of the
discretisation error (by default stress recovery on the same solve, :mod:`fea.error_estimate`; or a second solve
at 1.5 h and Richardson), written into the file's provenance with the mesh statistics, the Maxwell-Betti
symmetry defect of C_F and the solver used.
"""
from __future__ import annotations

from dataclasses import asdict

import logging
import time
from typing import Protocol

import numpy as np

from rodlab.core.calc import calc_rod_compliance
from rodlab.core.joint_springs import declared_joint_compliance
from rodlab.core.progress import stages
from rodlab.core.compliance import RodCompliance
from rodlab.core.design import RodDesign
from rodlab.core.enums import ErrorEstimate, FeaModel, Method
from rodlab.core.errors import expect_type
from rodlab.core.fem_mesh import RodMesh

from .errors import FeaError
from .frame import CALIBRATION, FRAME_REVISION, asme_bend_flexibility, frame_compliance, frame_range_notes
from .joints import JointFit, joint_frame_compliance
from .ahead import SolveAhead, solve_ahead
from .mesh_request import DEFAULT_GRADING, MAX_DOFS, default_solid_size_mm, estimated_dofs, solid_mesh_request
from .solid import solve_compliance

__all__ = ["Mesher", "FeaModel", "compute_compliance", "solid_compliance", "default_solid_size_mm", "RICHARDSON_ORDER",
           "DEFAULT_GRADING", "estimated_dofs", "MAX_DOFS"]

log = logging.getLogger(__name__)

#: Observed convergence order of the tip compliance on curved-P2 rod meshes (rod 1#: 3.0-3.5).
RICHARDSON_ORDER = 3.0


class Mesher(Protocol):
    """What the solid model needs to mesh a design: ``rodlab.geometry.mesh_rod`` satisfies it. A mesher that
    works in the background may also offer ``linear_topology(design, **kw) -> LinearTopology | None``, the
    straight tetrahedra of the mesh it is making (:class:`rodlab.geometry.MeshPrefetch`): the solid model then
    makes its assembly plan from them while the mesh is finished (:func:`_solve_ahead`)."""

    def __call__(self, design: RodDesign, *, size_mm: float, grading, half: bool) -> RodMesh: ...


def _solve_ahead(design: RodDesign, mesher, kw: dict, backend: str | None) -> SolveAhead | None:
    """The assembly plan and the solver's analysis of the mesh ``mesher`` is making, from its straight tetrahedra
    (when it offers them, :class:`Mesher`), made while the mesher curves the elements; None otherwise."""
    offer = getattr(mesher, "linear_topology", None)
    topology = offer(design, **kw) if offer is not None else None
    if topology is None:
        return None
    try:
        ahead = solve_ahead(topology, backend)
    except Exception as e:  # noqa: BLE001 - optional work: the solve makes the plan and analysis itself then
        log.warning("no plan made beside the mesher (%s: %s); the solve makes it", type(e).__name__, e)
        return None
    log.info("assembly plan and analysis of %s from the straight mesh, beside the mesher: %.2f s", design.name,
             ahead.seconds)
    return ahead


def _coarse_solve(design, mesher, size_mm, grading, symmetry, backend, bar):
    """The coarser solve of the Richardson error estimate."""
    with bar.step("mesh (coarse)"):
        rc = mesher(design, size_mm=size_mm, grading=grading, half=symmetry)
    with bar.step("solve (coarse)"):
        return solve_compliance(design, rc, backend=backend)


def _estimate_kind(value) -> ErrorEstimate:
    """``error_estimate`` as an :class:`ErrorEstimate` (``True``: recovery, ``False``: none)."""
    if isinstance(value, bool):
        return ErrorEstimate.RECOVERY if value else ErrorEstimate.NONE
    try:
        return ErrorEstimate.parse(value, "error estimate")
    except ValueError as e:
        raise FeaError(str(e), key="error_estimate") from None


def _error_provenance(errF: np.ndarray, errg: np.ndarray, CF: np.ndarray, Cg: np.ndarray, method: str) -> dict:
    """The provenance's ``discretisation_error``: the estimated error of every entry and the largest relative."""
    return {"method": method, "C_F_mm_per_N": errF.tolist(), "C_g_mm_per_g0": errg.tolist(),
            "max_relative_C_F": float(errF.max() / np.abs(CF).max()),
            "max_relative_C_g": float(errg.max() / np.abs(Cg).max()),
            "relative_diagonal_C_F": (np.diag(errF) / np.abs(np.diag(CF))).tolist()}


def solid_compliance(design: RodDesign, mesher, size_mm: float | None = None,
                     error_estimate: ErrorEstimate | str | bool = ErrorEstimate.RECOVERY,
                     grading=DEFAULT_GRADING, backend: str | None = None, keep_displacements: bool = False,
                     symmetry: bool = True, tip_moments: bool = False, plans=None):
    """Solid-FEA :class:`~rodlab.core.compliance.RodCompliance` (method ``fea``) and the raw result.

    ``mesher`` (:class:`Mesher`, called by keyword) makes the meshes: ``rodlab.geometry.mesh_rod`` as it is (the
    domain packages meet through the core's :class:`~rodlab.core.fem_mesh.RodMesh`, never import each other).
    ``symmetry=True`` asks it for the half ``y_T >= 0`` (``half=True``); ``False`` meshes the whole rod.
    ``error_estimate``: :class:`~rodlab.core.enums.ErrorEstimate` (``True`` is recovery, ``False`` none).
    ``plans``: a :class:`~fea.plan_cache.PlanCache` that keeps the mesh's node ordering and block pattern between
    runs (None: made anew).
    """
    how = _estimate_kind(error_estimate)
    request = solid_mesh_request(design, size_mm, grading, symmetry)
    h = request.size_mm
    richardson = how is ErrorEstimate.RICHARDSON
    names = ["mesh", "solve"] + (["mesh (coarse)", "solve (coarse)"] if richardson else [])
    with stages(f"solid FEA of {design.name}", names) as bar:
        with bar.step("mesh"):
            t0 = time.perf_counter()
            ahead = _solve_ahead(design, mesher, request.kwargs, backend)
            rm = mesher(design, **request.kwargs)
            t_mesh = time.perf_counter() - t0
        with bar.step("solve"):
            res = solve_compliance(design, rm, keep_displacements=keep_displacements, backend=backend,
                                   tip_moments=tip_moments, error_estimate=how is ErrorEstimate.RECOVERY, plans=plans,
                                   ahead=ahead)
        coarse = _coarse_solve(design, mesher, 1.5 * h, grading, symmetry, backend, bar) if richardson else None
    prov = {"generator": "rodlab solid FEA (scikit-fem, curved P2 tetrahedra)",
            "model": "solid", "mesh": dict(rm.stats, sha256=rm.sha256, grading=list(grading) if grading else None),
            "dofs": res.dofs, "solver": res.backend,
            "symmetry": ("half mesh y_T >= 0, symmetric + antisymmetric solves" if rm.is_half else "whole mesh"),
            "symmetry_defect_C_F": res.symmetry_defect,
            "mesh_mass_kg": res.mass_kg, "timings_s": dict({k: round(v, 3) for k, v in res.timings_s.items()},
                                                            mesh=round(t_mesh, 3)),
            "materials": {"transverse_isotropy": "axis = local tube axis", "nu23_assumed": 0.4}}
    dF, dg = declared_joint_compliance(design)        # the design's declared compliant joints, in series
    CF, Cg = res.C_F + dF, res.C_g + dg
    if coarse is not None:
        factor = 1.5 ** RICHARDSON_ORDER - 1.0
        prov["discretisation_error"] = _error_provenance(
            np.abs(res.C_F - coarse.C_F) / factor, np.abs(res.C_g - coarse.C_g) / factor, CF, Cg,
            f"Richardson, sizes {h:g} and {1.5 * h:g} mm, assumed order {RICHARDSON_ORDER:g}")
    elif res.error_matrix is not None:
        E = res.error_matrix
        prov["discretisation_error"] = _error_provenance(
            np.abs(E[:3, :3]), np.abs(E[:3, 3:6]), CF, Cg,
            "stress recovery (Zienkiewicz-Zhu) on the solve's mesh: the energy of the recovered minus the computed "
            "stress between the load cases; the computed compliance is too small by this much or more (it sees "
            "0.3-0.6 of the error at the sleeves' corners: docs/benchmarks/fea_error_estimate.md)")
    CF = 0.5 * (CF + CF.T)
    return RodCompliance.from_design(design, CF, Cg, Method.FEA, prov), res


def compute_compliance(design: RodDesign, model: FeaModel | str = FeaModel.FRAME, mesher=None,
                       **kwargs) -> RodCompliance:
    """Compliance of ``design`` by ``model`` (``solid`` needs a ``mesher``, see :func:`solid_compliance`).

    ``calibration`` (frame only): a :class:`fea.frame.FrameCalibration` (constants) or a
    :class:`fea.joints.JointFit` (one solid run of the design's family, :mod:`fea.family`)."""
    expect_type(design, RodDesign, "design", "load one with rodlab.resolve_design('rod1' or 'FILE.rod.toml')")
    try:
        model = FeaModel(model)
    except ValueError as e:
        raise FeaError(f"model {model!r}: expected one of {[m.value for m in FeaModel]}", key="model") from e
    if model is FeaModel.SOLID:
        if mesher is None:
            raise FeaError("the solid model needs a mesher (geometry.mesh_rod)", key="mesher")
        return solid_compliance(design, mesher, **kwargs)[0]
    calibration = kwargs.pop("calibration", None)
    if kwargs:
        raise FeaError(f"options {sorted(kwargs)} apply to the solid model only", key="model")
    if model is FeaModel.FRAME:
        if isinstance(calibration, JointFit):
            CF, Cg = joint_frame_compliance(design, calibration)
            b = calibration.base
            return RodCompliance.from_design(design, CF, Cg, Method.FEA, {
                "generator": "rodlab beam frame (Timoshenko, unit-load method), joint-calibrated on solid FEA",
                "model": "frame", "frame_revision": FRAME_REVISION,
                "joint_calibration": {"solid_design": b.name, "L1_mm": b.L1_mm, "L2_mm": b.L2_mm,
                                      "margins_mm": list(calibration.margins_mm),
                                      "block_asymmetry": calibration.asymmetry,
                                      "span_residual": calibration.span_residual},
                "outside_calibrated_range": []})
        cal = calibration or CALIBRATION
        k = asme_bend_flexibility(design, cal)
        CF, Cg = frame_compliance(design, cal=cal)
        notes = [] if calibration is not None else frame_range_notes(design)
        for note in notes:
            log.info("frame model of %s: %s; check it with the solid model", design.name, note)
        return RodCompliance.from_design(design, CF, Cg, Method.FEA, {
            "generator": "rodlab beam frame (Timoshenko, unit-load method)", "model": "frame",
            "frame_revision": FRAME_REVISION,
            "bend_flexibility": {"in_plane": k.in_plane, "out_of_plane": k.out_of_plane,
                                 "applies_to": "the arc between its restrained ends"},
            "calibration": dict(asdict(cal), family=calibration is not None),
            "outside_calibrated_range": notes})
    return calc_rod_compliance(design)
