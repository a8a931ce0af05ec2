"""Conformal multi-part tetrahedral mesh of a rod with gmsh, and its scikit-fem form.

The parts' OCC solids are imported into gmsh and fragmented together, so bonded interfaces
(tube in ring, tube in holder, plug in bore, stud in ball seat) share their nodes. One physical
volume per part (named as :class:`~rodlab.core.enums.Part`), physical surfaces ``flange_face`` (the
clamped face) and ``ball`` (the sphere). Quadratic elements are curved (``SecondOrderLinear = 0``):
straight-sided P2 tets make a tube's section an inscribed polygon. Meshing runs single-threaded
so that the same inputs give a bit-identical mesh.
"""
from __future__ import annotations

import hashlib
import logging
import os
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part, SegmentKind
from rodlab.core.fileio import atomic_write_bytes
from rodlab.core.fem_mesh import LinearTopology, RodMesh
from rodlab.core.layout import layout

from .cadlib import build123d
from .errors import GeometryError
from .gmsh_signals import initialize_gmsh
from .mesh_elements import elements, linear_topology
from .mesh_generate import generate_mesh, session_options
from .mesh_size import check_element_count, default_size_mm
from .parts import half_solids, part_solids
from .occ_parts import add_part_volumes

__all__ = ["mesh_rod", "default_size_mm", "feature_circles", "GMSH_TO_VTK_TET10"]

log = logging.getLogger(__name__)
_GMSH_LOCK = threading.Lock()   # gmsh has global state

#: gmsh tet10 node order (v0..v3, e01, e12, e02, e03, e23, e13) -> VTK / skfem / CalculiX (.., e13, e23)
GMSH_TO_VTK_TET10 = np.array([0, 1, 2, 3, 4, 5, 6, 7, 9, 8])


def feature_circles(design: RodDesign) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Circles where the section changes (sleeve ends, bend tangents, clamp, seat): stress concentrations.

    Returns centres (n, 3) in {T} [mm], unit normals (n, 3) and radii (n,) [mm].
    """
    centres, normals, radii = [], [], []
    segs = layout(design)
    for seg in segs:
        for u in (0.0, seg.length_mm):
            c = seg.point([u])[0] - design.tool_mm
            t = seg.tangent([u])[0]
            for layer in seg.layers:
                for d in (layer.d_out_mm, layer.d_in_mm):
                    if d > 0:
                        centres.append(c)
                        normals.append(t)
                        radii.append(d / 2.0)
    return np.array(centres), np.array(normals), np.array(radii)


#: Parts whose section changes get the fine size (the thin tubes, where the stress concentrates); the stiff
#: sleeves, holders and the ball take the size ``h`` away from the faces they share with the tubes.
GRADED_PARTS = (Part.PIPE_I, Part.BEND, Part.PIPE_II)


def _grading_field(design: RodDesign, h_near: float, h_far: float, growth: float,
                   graded_volumes: list[int], bend_volumes: list[int], h_bend: float) -> None:
    """Background size field of the graded mesh: inside ``graded_volumes`` ``min(h_far, h_near + growth * d)``
    with ``d`` the distance to the nearest feature circle (gmsh Distance + Threshold fields, evaluated natively:
    a Python size callback cost ~2 s per mesh); at most ``h_bend`` inside ``bend_volumes`` (the thin bend
    ovalises: its flexibility converges more slowly than the straight tubes'). The feature circles are the
    model's curves that lie on them."""
    import gmsh

    centres, normals, radii = feature_circles(design)

    def on_feature(tag: int) -> bool:
        lo, hi = gmsh.model.getParametrizationBounds(1, tag)
        u = np.linspace(lo[0], hi[0], 5)
        xyz = np.asarray(gmsh.model.getValue(1, tag, u)).reshape(-1, 3)
        for x in xyz:
            p = x - centres
            a = np.einsum("ij,ij->i", p, normals)
            radial = np.sqrt(np.maximum(np.einsum("ij,ij->i", p, p) - a * a, 0.0))
            if np.sqrt(a * a + (radial - radii) ** 2).min() > 1e-4 * max(radii.max(), 1.0):
                return False
        return True

    field = gmsh.model.mesh.field

    def restrict(f: int, volumes: list[int]) -> int:
        r = field.add("Restrict")
        field.setNumber(r, "InField", f)
        field.setNumbers(r, "VolumesList", volumes)
        return r

    fields = []
    curves = [t for d, t in gmsh.model.getEntities(1) if on_feature(t)]
    if curves and graded_volumes:
        f_dist = field.add("Distance")
        field.setNumbers(f_dist, "CurvesList", curves)
        field.setNumber(f_dist, "Sampling", 64)
        f_thr = field.add("Threshold")
        field.setNumber(f_thr, "InField", f_dist)
        field.setNumber(f_thr, "SizeMin", h_near)
        field.setNumber(f_thr, "SizeMax", h_far)
        field.setNumber(f_thr, "DistMin", 0.0)
        field.setNumber(f_thr, "DistMax", (h_far - h_near) / growth)
        fields.append(restrict(f_thr, graded_volumes))
    if bend_volumes and h_bend < h_far:
        f_c = field.add("MathEval")
        field.setString(f_c, "F", repr(float(h_bend)))
        fields.append(restrict(f_c, bend_volumes))
    if not fields:
        return
    if len(fields) > 1:
        f_min = field.add("Min")
        field.setNumbers(f_min, "FieldsList", fields)
        fields = [f_min]
    field.setAsBackgroundMesh(fields[0])


def _check_grading(grading) -> tuple[float, float, float] | None:
    """``(near, growth[, bend])`` validated; ``bend`` defaults to 1 (no extra refinement of the bend)."""
    if grading is None:
        return None
    try:
        g = tuple(float(v) for v in grading)
    except (TypeError, ValueError) as e:
        raise GeometryError(f"grading must be (near_factor, growth[, bend_factor]) numbers, got {grading!r}",
                            key="grading") from e
    if len(g) == 2:
        g = g + (1.0,)
    if len(g) != 3 or not (0 < g[0] <= 1 and g[1] > 0 and 0 < g[2] <= 1) or not all(np.isfinite(g)):
        raise GeometryError(f"grading must be (near_factor in (0, 1], growth > 0[, bend_factor in (0, 1]]), "
                            f"got {grading!r}", key="grading")
    return g


def _tube_axes(design: RodDesign, centroids_T: np.ndarray) -> np.ndarray:
    """The centreline's tangent nearest to each element centroid, shape=(n, 3): on a straight segment its
    direction (the nearest point by projection), on a bend the tangent of the nearest of its samples (2 per mm)."""
    best = np.full(len(centroids_T), np.inf)
    axes = np.zeros((len(centroids_T), 3))
    for seg in layout(design):
        if seg.kind is SegmentKind.LINE:
            p0 = seg.start_F - design.tool_mm
            u = np.clip((centroids_T - p0) @ seg.direction, 0.0, seg.length_mm)
            d2 = ((centroids_T - p0 - u[:, None] * seg.direction) ** 2).sum(axis=1)
            tan = np.broadcast_to(seg.direction, centroids_T.shape)
        else:
            u = np.linspace(0.0, seg.length_mm, max(int(seg.length_mm * 2.0), 2))
            d2, k = _nearest_arc_sample(centroids_T, seg, u, design.tool_mm)
            tan = seg.tangent(u)[k]
        closer = d2 < best
        best[closer], axes[closer] = d2[closer], tan[closer]
    return axes


def _nearest_arc_sample(x: np.ndarray, seg, u: np.ndarray, tool_mm) -> tuple[np.ndarray, np.ndarray]:
    """Squared distance to the nearest of the arc's samples at arc lengths ``u`` (uniform) and its index, for every
    row of ``x`` [mm, {T}]: the distance to a circle's point grows with the angle from the point's own angle on it,
    so the nearest sample is a neighbour of that angle, or an end of the arc."""
    t0, n = seg.direction, seg.tangent([seg.radius_mm * np.pi / 2.0])[0]
    v = x - (seg.start_F - tool_mm + seg.radius_mm * n)                # from the arc's centre
    theta = np.arctan2(v @ t0, -(v @ n))                                # 0 at the start, growing along it
    j = np.floor(np.clip(theta * seg.radius_mm, 0.0, u[-1]) / (u[1] - u[0])).astype(int)
    cand = np.stack([np.zeros_like(j), np.minimum(j, len(u) - 1), np.minimum(j + 1, len(u) - 1),
                     np.full_like(j, len(u) - 1)], axis=1)
    pts = seg.point(u) - tool_mm
    d2 = ((x[:, None, :] - pts[cand]) ** 2).sum(axis=2)
    best = d2.argmin(axis=1)
    return d2[np.arange(len(x)), best], cand[np.arange(len(x)), best]


def mesh_rod(design: RodDesign, size_mm: float | None = None, order: int = 2,
             msh_path: str | Path | None = None, grading: tuple[float, ...] | None = None,
             half: bool = False, kernel: str = "gmsh",
             on_topology: Callable[[LinearTopology], None] | None = None) -> RodMesh:
    """Mesh ``design`` with gmsh; optionally write ``msh_path`` (gmsh 4.1, atomically).

    ``half=True`` meshes only the half ``y_T >= 0``: every rod is mirror-symmetric about its bend plane
    ``y_T = 0`` (straight tubes and holders along axes in that plane, the bend revolved about an axis along
    ``y_T``, the ball on it), so the solid FEA solves two half-size problems instead of one (see
    :func:`fea.solve_compliance`). The cut face becomes ``symmetry_face`` / ``RodMesh.symmetry_facets``.

    ``grading = (near_factor, growth[, bend_factor])``: inside the tubes (:data:`GRADED_PARTS`) element size
    ``near_factor * size`` at the circles where the section changes (sleeve ends, bend tangents, clamp: stress
    concentrations), growing by ``growth`` mm per mm of distance up to ``size``; at most
    ``bend_factor * size`` (default 1) in the bend. The stiff sleeves, holders and ball take ``size`` away from
    the faces they share with the tubes. ``None``: uniform size.

    ``kernel``: ``gmsh`` builds the parts in gmsh's own OpenCASCADE kernel (:mod:`geometry.occ_parts`; no
    build123d import), ``build123d`` imports the CAD assembly's solids (:func:`geometry.parts.part_solids`):
    the same geometry.

    ``on_topology``: for an order-2 mesh, called once (in the caller's thread) with the straight tetrahedra
    (:class:`~rodlab.core.fem_mesh.LinearTopology`) before gmsh curves them: the same mesh, made in two steps
    (:func:`geometry.mesh_generate.generate_mesh`), so that a solver can plan its assembly meanwhile.

    Raises :class:`~geometry.errors.GeometryError` on a mesh with inverted elements or missing parts.
    """
    import gmsh

    h, grading = _check_mesh_args(design, size_mm, order, grading, kernel)
    solids = None
    if kernel == "build123d":
        solids = part_solids(design)
        if half:
            solids = half_solids(solids)
    with _GMSH_LOCK, tempfile.TemporaryDirectory(prefix="rodlab-mesh-") as tmp:
        initialize_gmsh()
        try:
            session_options()
            gmsh.model.add(f"rod_{design.name}")
            solids, part_vols = _model(design, solids, half, tmp)
            _size_and_order(design, part_vols, h, order, grading)
            t0 = time.perf_counter()
            on_linear = None if on_topology is None else lambda: _hand_over(on_topology, solids, part_vols)
            high_order = generate_mesh(order, on_linear)
            log.info("gmsh generate: %.2f s", time.perf_counter() - t0)
            node_tags, coords, _ = gmsh.model.mesh.getNodes()
            conn, part_idx, qual = elements(solids, part_vols, order)
            if msh_path is not None:
                _write_msh(msh_path, tmp)
        finally:
            gmsh.finalize()
    return _to_skfem(design, solids, node_tags, coords.reshape(-1, 3), conn, part_idx, qual, h, order, msh_path, half,
                     high_order)


def _model(design: RodDesign, solids, half: bool, tmp: str) -> tuple[dict, dict]:
    """The parts in the current gmsh model, fragmented into one conforming model with a physical group each: built in
    gmsh's OCC kernel (``solids`` None) or imported from build123d's; (solids, {part: volume tags})."""
    if solids is None:
        solids = add_part_volumes(design, half)
        part_vols = _fragment(solids)
    else:
        part_vols = _import_parts(solids, tmp)
    _physical_groups(design, solids, part_vols, half)
    return solids, part_vols


def _size_and_order(design: RodDesign, part_vols: dict, h: float, order: int, grading) -> None:
    """The element size (graded in the tubes when ``grading`` is given), order and algorithms."""
    if grading is not None:
        graded = sorted({v for p in GRADED_PARTS for v in part_vols.get(p, [])})
        _grading_field(design, grading[0] * h, h, grading[1], graded, part_vols.get(Part.BEND, []), grading[2] * h)
    _mesh_options(h, order, grading)


def _write_msh(msh_path, tmp: str) -> None:
    """The current mesh as gmsh 4.1 at ``msh_path``, atomically."""
    import gmsh

    out = os.path.join(tmp, "rod.msh")
    gmsh.write(out)
    atomic_write_bytes(msh_path, Path(out).read_bytes())


def _hand_over(on_topology: Callable[[LinearTopology], None], solids: dict, part_vols: dict) -> None:
    """``on_topology(the straight mesh's tetrahedra)``: optional work for the caller, so a failure is logged and
    the mesh goes on (the caller then has no topology and does that work on the finished mesh)."""
    try:
        on_topology(linear_topology(solids, part_vols))
    except Exception as e:  # noqa: BLE001 - never fail the mesh for the caller's optional work
        log.warning("the straight mesh was not handed over (%s: %s); meshing goes on", type(e).__name__, e)


def _check_mesh_args(design: RodDesign, size_mm, order, grading, kernel) -> tuple[float, tuple | None]:
    """The element size [mm] (the design's default when ``size_mm`` is None) and the checked grading."""
    if kernel not in ("gmsh", "build123d"):
        raise GeometryError(f"kernel must be gmsh or build123d, got {kernel!r}", key="kernel")
    if order not in (1, 2):
        raise GeometryError(f"order must be 1 or 2, got {order!r}", key="order")
    h = default_size_mm(design, order) if size_mm is None else float(size_mm)
    if not (h > 0 and np.isfinite(h)):
        raise GeometryError(f"size must be a positive number of mm, got {size_mm!r}", key="size")
    check_element_count(design, h, order)
    return h, _check_grading(grading)


def _import_parts(solids: dict, tmp: str) -> dict:
    """Import each part's build123d solid into gmsh and fragment them into one conforming model; returns
    {part: its gmsh volume tags} (a part may split into several volumes)."""
    bd = build123d()
    import gmsh

    src = {}
    for part, solid in solids.items():
        f = os.path.join(tmp, f"{part.value}.brep")
        bd.export_brep(solid, f)
        src[part] = [dt for dt in gmsh.model.occ.importShapes(f, highestDimOnly=True) if dt[0] == 3]
    return _fragment(src)


def _fragment(src: dict) -> dict:
    """Fragment the parts' volumes ({part: [(3, tag)]}) into one conforming model; returns {part: its gmsh
    volume tags} (a part may split into several volumes)."""
    import gmsh

    src = list(src.items())
    objects = [dt for _, vols in src for dt in vols]
    _, out_map = gmsh.model.occ.fragment(objects, [])
    gmsh.model.occ.synchronize()
    part_vols: dict[Part, list[int]] = {}
    k = 0
    for part, vols in src:
        for _ in vols:
            part_vols.setdefault(part, []).extend(t for d, t in out_map[k] if d == 3)
            k += 1
    for part, _ in src:
        if not part_vols.get(part):
            raise GeometryError(f"part {part} vanished when the parts were fused; check its dimensions",
                                key=str(part))
    return part_vols


def _physical_groups(design: RodDesign, solids: dict, part_vols: dict, half: bool) -> None:
    """One volume group per part (tag = its index + 1), and the surface groups the FEA needs: the flange face
    (clamp), the ball's sphere (load), and on a half mesh the cut face on ``y_T = 0``."""
    import gmsh

    for i, part in enumerate(solids):
        gmsh.model.addPhysicalGroup(3, sorted(set(part_vols[part])), tag=i + 1, name=str(part))
    z0 = -design.tool_mm[2]
    x0 = -design.tool_mm[0]
    eps = 1e-3
    flange = [t for d, t in gmsh.model.getEntitiesInBoundingBox(
        x0 - 1e3, -1e3, z0 - eps, x0 + 1e3, 1e3, z0 + eps, dim=2)]
    if not flange:
        raise GeometryError("no flange face found at the flange plane", key="pipe_I")
    gmsh.model.addPhysicalGroup(2, flange, name="flange_face")
    ball_surf = sorted({t for v in part_vols[Part.BALL]
                        for d, t in gmsh.model.getBoundary([(3, v)], oriented=False)
                        if gmsh.model.getType(2, t) == "Sphere"})
    gmsh.model.addPhysicalGroup(2, ball_surf, name="ball")
    if half:
        cut = [t for d, t in gmsh.model.getEntitiesInBoundingBox(-1e4, -eps, -1e4, 1e4, eps, 1e4, dim=2)]
        if not cut:
            raise GeometryError("the half mesh has no face on the symmetry plane y_T = 0", key="half")
        gmsh.model.addPhysicalGroup(2, cut, name="symmetry_face")


def _mesh_options(h: float, order: int, grading) -> None:
    """gmsh's size, order and algorithm options for the rod."""
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMax", h)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.05 * h * (grading[0] if grading else 1.0))
    gmsh.option.setNumber("Mesh.MeshSizeFromCurvature", 12)
    # the 1-D mesher integrates the size field along each curve; gmsh's default precision (1e-9) spent
    # ~1.2 s of rod 1#'s ~2.5 s mesh on it with the distance field; 1e-3 moves nodes by < 0.1 % of h
    gmsh.option.setNumber("Mesh.LcIntegrationPrecision", 1e-3)
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 1 if order == 2 else 0)   # untangle curved P2
    gmsh.option.setNumber("Mesh.Algorithm", 6)      # Frontal-Delaunay surfaces
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)   # HXT: ~25 % faster than Delaunay, same quality


def _to_skfem(design, solids, node_tags, coords, conn, part_idx, qual, h, order, msh_path, half=False,
              high_order: int = 0):
    from rodlab.core.skfem_tet import MeshTet1Keyed, MeshTet2Keyed  # heavy: skfem (scikit-fem, ~0.2 s)

    index = np.full(int(node_tags.max()) + 1, -1, dtype=np.int64)
    index[node_tags.astype(np.int64)] = np.arange(node_tags.size)
    t = index[conn.astype(np.int64)]
    used = np.unique(t)
    remap = np.full(node_tags.size, -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    t = remap[t]
    p = coords[used]
    if order == 2:
        t = t[:, GMSH_TO_VTK_TET10]
        mesh = MeshTet2Keyed(p.T.copy(), t.T.copy())
    else:
        mesh = MeshTet1Keyed(p.T.copy(), t.T.copy())
    worst = float(qual.min())
    if worst <= 0:
        raise GeometryError(f"rod {design.name!r}: the mesh has inverted elements (worst quality {worst:.3g}); "
                            f"use a smaller --size than {h:g} mm", key="size")
    centroids = mesh.p[:, mesh.t].mean(axis=1).T
    axes = _tube_axes(design, centroids)
    z0 = -design.tool_mm[2]
    flange = mesh.facets_satisfying(lambda x: np.abs(x[2] - z0) < 1e-6, boundaries_only=True)
    r = design.ball.radius_mm          # the ball's sphere is centred on the {T} origin
    tol = max(h * h / (4 * r), 1e-3 * r)   # facet midpoints sit inside the sphere by the sagitta
    ball = mesh.facets_satisfying(lambda x: np.abs(np.linalg.norm(x, axis=0) - r) < tol, boundaries_only=True)
    sym = mesh.facets_satisfying(lambda x: np.abs(x[1]) < 1e-6, boundaries_only=True) if half else None
    digest = hashlib.sha256(np.round(p, 9).tobytes() + t.astype(np.int64).tobytes()).hexdigest()
    stats = {"nodes": int(p.shape[0]), "elements": int(t.shape[0]), "size_mm": h, "order": order,
             "min_quality_sicn": worst, "mean_quality_sicn": float(qual.mean()),
             "flange_facets": int(flange.size), "ball_facets": int(ball.size), "half": bool(half)}
    if high_order == 2:          # the optimizer gave up and the elastic analogy went first (geometry.mesh_generate)
        stats["high_order_optimize"] = "elastic+optimization"
    return RodMesh(mesh, tuple(solids), part_idx.astype(np.int32), axes, flange, ball, h, order, worst, digest,
                   None if msh_path is None else Path(msh_path), stats=stats, symmetry_facets=sym)
