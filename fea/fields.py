"""The solid FEA's fields for ParaView and pyvista: displacements and von Mises stress of the six unit load cases
on the whole rod's mesh, written as one VTK unstructured grid (``.vtu``); the frame model's centreline (``.vtp``).

A separate step after the solve (it needs the kept displacements, :func:`~fea.solid.solve_compliance` with
``keep_displacements``): a half mesh is mirrored into the whole rod, each field symmetric or antisymmetric about
``y_T = 0`` as its load case. Stress: ``sigma = C : sym(grad u)`` with each element's own stiffness tensor,
evaluated at the element's 10 nodes (exact for P2: linear in the element) and averaged over the elements around
each node (across a bonded joint the average of the two materials' stresses). Coordinates [mm] in the flange
frame {6} (``{T}`` shifted by the ball centre ``tool_mm``; the axes are parallel), vectors along x, y, z of
{6} = {T}. The frame's centreline carries the same displacement arrays and the sections' outer-fibre von Mises
stress from the beam's section forces (:mod:`fea.beam_stress`).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.core.chain import centreline_points, chain_flexibility, transport
from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.massprops import ball_mass_properties
from rodlab.core.vtkio import VTK_QUADRATIC_TETRA, VTK_TETRA, VtkData, write_vtp, write_vtu

from .elasticity import element_tensors
from .error_estimate import node_basis
from .errors import FeaError
from .frame import CALIBRATION, frame_segments
from .solid import SolidResult, mirror_displacements
from .beam_stress import section_index, section_von_mises, section_wrenches
from .stiffness_assembly import scalar_element

__all__ = ["LOAD_CASE_KEYS", "LOAD_CASE_TEXT", "SolidFields", "solid_fields", "write_solid_fields",
           "write_frame_fields", "field_data", "FrameFields", "frame_centreline_fields", "nodal_von_mises"]

#: load cases in column order: unit force along x, y, z of {T} [N] at the ball centre, then 1 g0 along x, y, z
LOAD_CASE_KEYS = ("Fx", "Fy", "Fz", "gx", "gy", "gz")
LOAD_CASE_TEXT = ("unit force along +x_T at the ball centre", "unit force along +y_T at the ball centre",
                  "unit force along +z_T at the ball centre", "self-weight, 1 g0 along +x_T",
                  "self-weight, 1 g0 along +y_T", "self-weight, 1 g0 along +z_T")


def _per(k: int) -> str:
    return "per N" if k < 3 else "per g0"


@dataclass
class SolidFields:
    """Fields of the six unit load cases on the whole rod.

    points_mm : node positions [mm] in {6}, shape=(N, 3); cells : node indices of each element in VTK's order,
    shape=(n_el, 10) (quadratic) or (n_el, 4); part_index : element -> index into ``parts``, shape=(n_el,);
    parts : part names; displacement : [mm per N | mm per g0] along x, y, z of {T}, shape=(N, 3, 6);
    von_mises : [MPa per N | MPa per g0], shape=(N, 6); ball_centre_mm : the ball centre in {6} (``tool_mm``),
    shape=(3,); ball_displacement : the ball centre's displacement (rigid fit of the ball, = the columns of C_F
    and C_g) [mm per unit load], shape=(3, 6); rod : the design's name
    """

    points_mm: np.ndarray
    cells: np.ndarray
    part_index: np.ndarray
    parts: tuple
    displacement: np.ndarray
    von_mises: np.ndarray
    ball_centre_mm: np.ndarray
    ball_displacement: np.ndarray
    rod: str

    def __post_init__(self) -> None:
        n, m = self.points_mm.shape[0], self.cells.shape[0]
        for name, shape in (("points_mm", (n, 3)), ("part_index", (m,)), ("displacement", (n, 3, 6)),
                            ("von_mises", (n, 6)), ("ball_centre_mm", (3,)), ("ball_displacement", (3, 6))):
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"SolidFields.{name} must have shape {shape}, got {np.shape(getattr(self, name))}")
        if self.cells.shape[1] not in (4, 10):
            raise ValueError(f"SolidFields.cells must have 4 or 10 nodes per element, got {self.cells.shape[1]}")


def nodal_von_mises(basis, C: np.ndarray, U: np.ndarray, chunk: int = 4000) -> np.ndarray:
    """Von Mises stress [N/mm^2 = MPa] per unit load at every node, shape=(N, n_cases), from the displacements
    ``U`` shape=(3 N, n_cases) [mm] and the element tensors ``C`` shape=(n_el, 3, 3, 3, 3) [N/mm^2]: evaluated
    at each element's nodes (``basis`` from :func:`~fea.error_estimate.node_basis`) and averaged over the elements at a node."""
    nloc = len(basis.basis)
    ed = basis.element_dofs                                      # (nloc, ne); quadrature point q = local node q
    ne, n_cases = ed.shape[1], U.shape[1]
    Un = U.reshape(-1, 3, n_cases)
    total = np.zeros((basis.N, n_cases))
    count = np.bincount(ed.ravel(), minlength=basis.N).astype(float)
    G = np.stack([basis.basis[a][0].grad for a in range(nloc)])   # (a, k, e, q)
    for s in range(0, ne, chunk):
        e = slice(s, min(s + chunk, ne))
        grad = np.einsum("aeic,akeq->eqcik", Un[ed[:, e]], G[:, :, e, :], optimize=True)   # du_i/dx_k
        eps = 0.5 * (grad + np.swapaxes(grad, -1, -2))
        sig = np.einsum("eijkl,eqckl->eqcij", C[e], eps, optimize=True)
        dev = sig - np.trace(sig, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) / 3.0
        vm = np.sqrt(1.5 * np.einsum("eqcij,eqcij->eqc", dev, dev))                  # (e, q, case)
        for c in range(n_cases):
            total[:, c] += np.bincount(ed[:, e].T.ravel(), weights=vm[:, :, c].ravel(), minlength=basis.N)
    return total / np.maximum(count, 1.0)[:, None]


def solid_fields(design: RodDesign, res: SolidResult) -> SolidFields:
    """The six load cases' fields of a solid result (solved with ``keep_displacements``) on the whole rod."""
    if res.displacements is None or res.rod_mesh is None:
        raise FeaError("the solid result kept no displacements: solve with keep_displacements=True",
                       key="displacements")
    rm, U = res.rod_mesh, res.displacements[:, :6]
    if rm.is_half:
        whole = rm.mirrored()
        U, rm = mirror_displacements(rm, U, whole), whole
    basis = node_basis(rm.mesh, scalar_element(rm.mesh))
    C = element_tensors([design.material_of(p) for p in rm.parts], rm.part_index, rm.tube_axis)
    vm = nodal_von_mises(basis, C, U)
    tool = np.asarray(design.tool_mm, dtype=float)
    return SolidFields(points_mm=basis.doflocs.T + tool, cells=basis.element_dofs.T.astype(np.int64),
                       part_index=rm.part_index.astype(np.int64), parts=tuple(str(p) for p in rm.parts),
                       displacement=U.reshape(-1, 3, 6), von_mises=vm, ball_centre_mm=tool,
                       ball_displacement=np.asarray(res.ball_motion[:3, :6] if res.ball_motion is not None
                                                    else np.hstack([res.C_F, res.C_g])),
                       rod=design.name)


def field_data(rod: str, ball_centre_mm: np.ndarray, ball_displacement: np.ndarray, model: str) -> dict:
    """What every rodlab field file carries besides its arrays (read by ``rodlab view``)."""
    return {"rod": [rod], "model": [model], "frame": ["coordinates [mm] in the flange frame {6}; vectors along x, "
                                                      "y, z of {T} (parallel to {6})"],
            "load_cases": list(LOAD_CASE_KEYS), "load_case_text": list(LOAD_CASE_TEXT),
            "units": ["mm per N"] * 3 + ["mm per g0"] * 3,
            "stress_units": ["MPa per N"] * 3 + ["MPa per g0"] * 3,
            "ball_centre_mm": np.asarray(ball_centre_mm, dtype=float)[None, :],
            "ball_displacement": np.asarray(ball_displacement, dtype=float).T}      # (6 cases, 3)


def write_solid_fields(path: str | Path, fields: SolidFields) -> Path:
    """Write ``fields`` as a VTK unstructured grid (``.vtu``; quadratic tetrahedra stay quadratic): point arrays
    ``displacement_<case>`` and ``von_mises_<case>`` for the cases :data:`LOAD_CASE_KEYS`, cell array ``part``
    (index into the field data's ``part_names``)."""
    pd = {}
    for k, key in enumerate(LOAD_CASE_KEYS):
        pd[f"displacement_{key}"] = fields.displacement[:, :, k]
    for k, key in enumerate(LOAD_CASE_KEYS):
        pd[f"von_mises_{key}"] = fields.von_mises[:, k]
    fd = dict(field_data(fields.rod, fields.ball_centre_mm, fields.ball_displacement, "solid"),
              part_names=list(fields.parts))
    ctype = VTK_QUADRATIC_TETRA if fields.cells.shape[1] == 10 else VTK_TETRA
    return write_vtu(path, fields.points_mm, fields.cells, ctype,
                     VtkData(point_data=pd, cell_data={"part": fields.part_index}, field_data=fd))


@dataclass
class FrameFields:
    """The frame model's centreline fields: points_mm [mm] in {6}, shape=(n, 3) (the first at the flange, the
    last the ball centre); displacement [mm per N | mm per g0] along x, y, z of {T}, shape=(n, 3, 6);
    von_mises : the section's outer-fibre stress [MPa per N | MPa per g0], shape=(n, 6); part_index : the part
    whose section holds each point (a ring or holder where it sleeves a tube), index into ``parts``,
    shape=(n,); parts : the part names, flange to ball."""

    points_mm: np.ndarray
    displacement: np.ndarray
    von_mises: np.ndarray
    part_index: np.ndarray
    parts: tuple

    def __post_init__(self) -> None:
        n = self.points_mm.shape[0]
        for name, shape in (("points_mm", (n, 3)), ("displacement", (n, 3, 6)), ("von_mises", (n, 6)),
                            ("part_index", (n,))):
            if np.shape(getattr(self, name)) != shape:
                raise ValueError(f"FrameFields.{name} must have shape {shape}, got {np.shape(getattr(self, name))}")


def frame_centreline_fields(design: RodDesign, n_points: int = 200) -> FrameFields:
    """The frame model's centreline (``n_points`` points [mm] in {6}), its displacements under the six unit
    load cases [mm per N | mm per g0], shape=(n, 3, 6): the section motions of the chain cut at every point
    (:func:`rodlab.core.chain.chain_flexibility`), the last point the ball centre (its displacement = C_F, C_g); and
    the sections' outer-fibre von Mises stress [MPa per N | MPa per g0], shape=(n, 6), from the section forces
    (:mod:`fea.beam_stress`)."""
    segs = frame_segments(design, CALIBRATION)
    total = segs[-1].s0_mm + segs[-1].length_mm
    s_all = np.linspace(0.0, total, n_points)
    cuts = s_all[1:-1]
    ball = ball_mass_properties(design)
    tool = np.asarray(design.tool_mm, dtype=float)
    ch = chain_flexibility(segs, cuts, tool, ball.mass_kg, ball.com_T_mm + tool, True, True,
                           CALIBRATION.shear, CALIBRATION.torsion)
    Ad = ch.adjoint()                                           # tip wrench -> wrench at each distal point
    own_F = np.einsum("nab,nbj->naj", ch.F, Ad[:, :, :3])      # interval motions per unit tip force (n, 6, 3)
    own_g = np.einsum("nab,nbj->naj", ch.F, ch.G) + ch.H         # per g0 (n, 6, 3)
    own = np.concatenate([own_F, own_g], axis=2)                 # (n, 6, 6 cases)
    P = ch.points_F
    motion = np.zeros((P.shape[0], 6, 6))
    for k in range(P.shape[0]):                                  # intervals 0..k carried rigidly to point k
        T = transport(P[k][None, :] - P[:k + 1])                 # (k+1, 6, 6)
        motion[k] = np.einsum("nba,nbc->ac", T, own[:k + 1])
    start = centreline_points(segs, [0.0])[0]
    points = np.vstack([start, P])
    disp = np.concatenate([np.zeros((1, 3, 6)), motion[:, :3, :]])
    vm = section_von_mises(segs, s_all, section_wrenches(segs, s_all, tool, ball.mass_kg, ball.com_T_mm + tool))
    names = [_section_part(segs[k]) for k in section_index(segs, s_all)]
    parts = tuple(str(p) for p in Part if str(p) in names)                # flange to ball
    return FrameFields(points, disp, vm, np.array([parts.index(n) for n in names], dtype=np.int64), parts)


_TUBES = ("pipe_I", "bend", "pipe_II")


def _section_part(seg) -> str:
    """The part a section shows: the ring or holder sleeving a tube where it carries load (not in its
    load-transfer zone, where the tube alone does), else the tube (or the holder alone)."""
    names = [str(layer.part) for layer in seg.layers if layer.part not in seg.slack] or [str(seg.layers[0].part)]
    return next((n for n in names if n not in _TUBES), names[0])


def write_frame_fields(path: str | Path, design: RodDesign, n_points: int = 200) -> Path:
    """The frame model's centreline as VTK poly data (``.vtp``): point arrays ``displacement_<case>`` and
    ``von_mises_<case>`` (the sections' outer-fibre stress from the beam's section forces) as in
    :func:`write_solid_fields`."""
    f = frame_centreline_fields(design, n_points)
    pd = {f"displacement_{key}": f.displacement[:, :, k] for k, key in enumerate(LOAD_CASE_KEYS)}
    pd.update({f"von_mises_{key}": f.von_mises[:, k] for k, key in enumerate(LOAD_CASE_KEYS)})
    fd = dict(field_data(design.name, design.tool_mm, f.displacement[-1], "frame"), part_names=list(f.parts))
    # one poly-line per run of points in one part (neighbouring runs share their end point), cell array ``part``
    starts = np.r_[0, np.nonzero(np.diff(f.part_index))[0] + 1]
    ends = np.r_[starts[1:], len(f.part_index) - 1]
    keep = ends > starts                                         # a last run of one point is the previous line's end
    lines = [np.arange(a, b + 1) for a, b in zip(starts[keep], ends[keep])]
    return write_vtp(path, f.points_mm, lines,
                     VtkData(point_data=pd, cell_data={"part": f.part_index[starts[keep]]}, field_data=fd))
