"""``rodlab fea``: compliance of a design by the solid FEA, the frame model or the closed form."""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from ...core.compliance import write_compliance
from ...core.design_io import resolve_design
from ...core.enums import ErrorEstimate, FeaModel
from ...core.errors import RenderError, RodlabError
from .argtypes import pos_float
from .cadextra import require_mesher
from .reporting import add_report_option, png_file, write_command_report
from .rodargs import design_help

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("fea", help="compute C_F and C_g by solid FEA (reference), beam frame or closed form",
                       description="Compute the compliance file of a rod design. "
                                   + "; ".join(f"{m.value}: {m.describes}" for m in FeaModel) + ".")
    p.add_argument("design", help=design_help())
    p.add_argument("-o", "--output", required=True, help="output *.compliance.json")
    p.add_argument("--model", choices=[m.value for m in FeaModel], default=FeaModel.SOLID.value,
                   help=f"the compliance model (default {FeaModel.SOLID.value}; frame: ~1 %% of it in milliseconds, "
                        "calc: the paper's closed form). The file's method is the contract's: fea for solid and "
                        "frame (its provenance's model says which: a calibrator's fea compensation takes either), "
                        "calc for calc")
    p.add_argument("--size", type=pos_float, default=None, help="solid: element size far from the section changes "
                   "[mm] (default 3 x the thinnest wall; inside the tubes graded down to 0.9 x wall at the section "
                   "changes, at most 2.1 x wall in the bend)")
    p.add_argument("--error-estimate", choices=[e.value for e in ErrorEstimate], default=ErrorEstimate.RECOVERY.value,
                   help="solid: how to estimate the discretisation error (into the file's provenance): "
                        + "; ".join(f"{e.value}: {e.describes}" for e in ErrorEstimate)
                        + f" (default {ErrorEstimate.RECOVERY.value})")
    p.add_argument("--no-error-estimate", action="store_true", help="solid: the same as --error-estimate none")
    p.add_argument("--no-cache", action="store_true",
                   help="solid: mesh and order the mesh again even when the same design and size were solved before "
                        "(meshes and their assembly plans are cached per user in ~/.cache/rodlab/meshes and plans, or "
                        "under $RODLAB_CACHE_DIR; RODLAB_CACHE_DIR=off turns the cache off)")
    p.add_argument("--no-symmetry", action="store_true",
                   help="solid: mesh and solve the whole rod instead of the half y_T >= 0 (same result, ~2x slower)")
    p.add_argument("--png", default=None, help="solid: the deformed shape (self-weight along -z_T): FILE.png, or a "
                                               "folder (it gets deformed.png, and with --report the 3-D views)")
    p.add_argument("--fields", default=None, metavar="OUT",
                   help="solid: the displacement and von Mises stress fields of the six unit load cases on the mesh "
                        "(*.vtu, for ParaView and `rodlab view`); frame: the centreline's displacements and its sections' "
                        "outer-fibre von Mises stress (*.vtp)")
    p.add_argument("--joints-out", default=None, metavar="FILE",
                   help="solid: also calibrate the frame's joints on this run and write them (*.joints.json) for "
                        "frame runs and sweeps of the design's family (--joints)")
    p.add_argument("--joints", default=None, metavar="FILE",
                   help="frame: joint-calibrated by a *.joints.json of the design's family (same parts, any L1 / "
                        "L2): within ~0.3 %% of the solid model")
    add_report_option(p)
    p.set_defaults(func=cmd_fea)


def _estimate(args: argparse.Namespace) -> ErrorEstimate:
    if args.no_error_estimate and args.error_estimate != ErrorEstimate.RECOVERY.value:
        raise RodlabError(f"--no-error-estimate and --error-estimate {args.error_estimate} contradict each other; "
                          f"give one")
    return ErrorEstimate.NONE if args.no_error_estimate else ErrorEstimate(args.error_estimate)


def cmd_fea(args: argparse.Namespace) -> int:
    design = resolve_design(args.design)
    _check_fields_option(args)
    t0 = time.perf_counter()
    if args.model == FeaModel.SOLID.value:
        if args.joints:
            raise RodlabError("--joints applies to --model frame (with --model solid, --joints-out writes one)")
        mesher = _prefetching_mesher(args, design)
        from rodlab.fea import PlanCache, run_solid
        run = run_solid(design, mesher, size_mm=args.size, error_estimate=_estimate(args),
                        plans=PlanCache(None if args.no_cache else "default"),
                        symmetry=not args.no_symmetry, joints=bool(args.joints_out),
                        deformed_png=png_file(args.png, "deformed.png"),
                        keep_displacements=bool(args.fields or args.report is not None))
        comp, res = run.compliance, run.result
        prov = comp.provenance
        print(f"solid FEA of rod {design.name}: {prov['dofs']} DOFs ({prov['mesh']['elements']} curved tet10"
              f"{', half model' if res.rod_mesh.is_half else ''}), "
              f"solver {prov['solver']}, symmetry defect of C_F {prov['symmetry_defect_C_F']:.1e}")
        if getattr(mesher, "hits", 0):
            print(f"  mesh from the cache ({mesher.folder}; --no-cache meshes again)")
        if "discretisation_error" in prov:
            e = prov["discretisation_error"]
            print(f"  estimated discretisation error ({_estimate(args).value}): {100 * e['max_relative_C_F']:.3f} % of "
                  f"max|C_F|, {100 * e['max_relative_C_g']:.3f} % of max|C_g|")
        for fig in run.figures:
            print(f"  wrote {fig}")
        extra = _solid_views(args, design, res)
        if run.joints is not None:
            from rodlab.fea.joints_io import write_joints
            jc = run.joints
            out = write_joints(args.joints_out, jc, {"solid_dofs": prov["dofs"], "mesh_sha256": prov["mesh"]["sha256"]})
            print(f"  joint calibration (sections {jc.margins_mm[0]:.1f} / {jc.margins_mm[1]:.1f} mm from the free "
                  f"tubes' ends, span fit residual {100 * jc.span_residual:.2f} %): wrote {out}")
    else:
        if args.png or args.size is not None or args.no_symmetry or args.joints_out:
            raise RodlabError("--png, --size, --no-symmetry and --joints-out apply to --model solid only")
        from rodlab.fea import compute_compliance
        calibration = None
        if args.joints:
            if args.model != FeaModel.FRAME.value:
                raise RodlabError("--joints applies to --model frame")
            from rodlab.fea.joints_io import read_joints
            calibration = read_joints(args.joints)
        comp = compute_compliance(design, args.model, **({"calibration": calibration} if calibration else {}))
        extra = _frame_views(args, design)
        for note in comp.provenance.get("outside_calibrated_range") or []:
            print(f"  note: {note}; check this design with --model solid, or calibrate the frame on it "
                  "(rodlab sweep --calibrate)")
    path = write_compliance(comp, args.output)
    np.set_printoptions(precision=6, suppress=True)
    shown = lambda M: np.round(M, 6) + 0.0   # noqa: E731  (as printed: no "-0." for what rounds to zero)
    print(f"  C_F [mm/N] =\n{shown(comp.C_F)}\n  C_g [mm/g0] =\n{shown(comp.C_g)}")
    print(f"  c_rod = {comp.c_rod_um:.1f} um ({time.perf_counter() - t0:.1f} s); wrote {path}")
    written = [path] + [p for p in (png_file(args.png, "deformed.png"), args.joints_out) if p] + extra
    write_command_report(args, written, path.parent)
    return 0


def _prefetching_mesher(args: argparse.Namespace, design):
    """The solid model's mesher (cached unless ``--no-cache``), already at work on ``design`` in the background
    while the solver's modules load (a rerun of rod 1# ~0.2 s less), handing over the straight tetrahedra so that
    the assembly plan and the solver's analysis are made while gmsh curves them (:func:`rodlab.app.solid_mesher.
    solid_mesher`). The CAD extra, the size and the model's size limit are checked first."""
    from rodlab.app.solid_mesher import solid_mesher   # the core only: no solver imports yet
    require_mesher()
    _estimate(args)
    return solid_mesher(design, args.size, symmetry=not args.no_symmetry, cache=not args.no_cache)


def _check_fields_option(args: argparse.Namespace) -> None:
    """``--fields``: a .vtu for the solid model, a .vtp for the frame, nothing for the closed form."""
    if not args.fields:
        return
    want = {"solid": ".vtu", "frame": ".vtp"}.get(args.model)
    if want is None:
        raise RodlabError("--fields applies to --model solid (*.vtu) and --model frame (*.vtp)")
    if Path(args.fields).suffix.lower() != want:
        raise RodlabError(f"--fields {args.fields}: the {args.model} model writes a {want} file; name it *{want}")


def _solid_views(args: argparse.Namespace, design, res) -> list:
    """Write ``--fields``; with ``--report`` also the 3-D views of the unit forces (from a temporary field file
    when ``--fields`` is not given). Returns the pictures for the report."""
    if not (args.fields or args.report is not None):
        return []
    from rodlab.fea.fields import solid_fields, write_solid_fields

    from ..report.views import render_field_pngs
    fields = solid_fields(design, res)
    with tempfile.TemporaryDirectory() as tmp:
        path = write_solid_fields(args.fields or Path(tmp) / f"{design.name}.vtu", fields)
        if args.fields:
            print(f"  wrote {path} (displacements and von Mises stress of Fx Fy Fz gx gy gz; `rodlab view {path}`)")
        if args.report is None:
            return []
        try:
            out = Path(args.output)
            pngs = render_field_pngs(path, _views_stem(args, Path(args.fields).with_suffix("") if args.fields
                                                       else out.parent / out.name.split(".")[0]))
        except RenderError as e:
            print(f"  note: no 3-D views in the report: {e}")
            return []
    for p in pngs:
        print(f"  wrote {p}")
    return pngs


def _views_stem(args: argparse.Namespace, stem: Path) -> Path:
    """Where the 3-D views (``STEM.3d_Fx.png`` ...) go: into ``--png`` when it names a folder, as the other
    figures do, else beside ``stem``."""
    if args.png and Path(args.png).suffix.lower() != ".png":
        return Path(args.png) / stem.name
    return stem


def _frame_views(args: argparse.Namespace, design) -> list:
    """``--fields`` of the frame model: its centreline (*.vtp), and with ``--report`` its 3-D views."""
    if not args.fields:
        return []
    from rodlab.fea.fields import write_frame_fields
    path = write_frame_fields(args.fields, design)
    note = " (the constant-calibrated frame: the joint calibration changes C_F only)" if args.joints else ""
    print(f"  wrote {path} (centreline displacements and section von Mises stress of Fx Fy Fz gx gy gz{note})")
    if args.report is None:
        return []
    from ..report.views import render_field_pngs
    try:
        return render_field_pngs(path, _views_stem(args, path.with_suffix("")))
    except RenderError as e:
        print(f"  note: no 3-D views in the report: {e}")
        return []
