"""``rodlab cad`` and ``rodlab mesh``: the CAD assembly and the FEA mesh of a design (``cad`` extra)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from ...design_io import resolve_design
from ...errors import RodlabError
from .argtypes import pos_float
from .reporting import add_report_option, write_command_report

__all__ = ["register", "require_cad", "require_mesher"]

_DESIGN_HELP = "a *.rod.toml file, or a built-in design: rod1 .. rod6"


def require_cad():
    """Import the geometry package, or explain how to install the CAD extra."""
    try:
        import build123d  # noqa: F401
        import gmsh  # noqa: F401
        import rodlab.geometry as geometry
    except ImportError as e:
        raise RodlabError(f"this command needs the CAD extra ({e.name} is missing): pip install 'rodlab[cad]'") from e
    return geometry


def require_mesher():
    """The geometry package for meshing only (gmsh builds the parts itself: build123d is not imported), or
    explain how to install the CAD extra."""
    try:
        import gmsh  # noqa: F401
        import rodlab.geometry as geometry
    except ImportError as e:
        raise RodlabError(f"this command needs the CAD extra ({e.name} is missing): pip install 'rodlab[cad]'") from e
    return geometry


def register(sub) -> None:
    p = sub.add_parser("cad", help="build the CAD assembly: STEP, STL, PNG views, mass.json",
                       description="Build the rod as a multi-part CAD assembly (build123d) in the tool frame {T}; "
                                   "write DIR/rod.step (part names and colours), DIR/rod.stl, PNG views (iso, xz, "
                                   "xy, yz) and DIR/mass.json (per part and total: mass, COM in {T}, inertia).")
    p.add_argument("design", help=_DESIGN_HELP)
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.add_argument("--no-png", action="store_true", help="skip the PNG views")
    p.add_argument("--renderer", choices=["auto", "pyvista", "matplotlib"], default="auto",
                   help="PNG views: pyvista (viz extra; the renderer of rodlab view), matplotlib (anywhere), or "
                        "auto: pyvista where it renders off-screen (default)")
    add_report_option(p)
    p.set_defaults(func=cmd_cad)

    p = sub.add_parser("mesh", help="mesh the rod for FEA (gmsh, one physical volume per part)",
                       description="Conformal tetrahedral mesh of all parts (bonded interfaces share nodes), "
                                   "physical volumes named after the parts, physical surfaces flange_face and "
                                   "ball; gmsh 4.1 format.")
    p.add_argument("design", help=_DESIGN_HELP)
    p.add_argument("-o", "--output", required=True, help="output .msh file")
    p.add_argument("--size", type=pos_float, default=None,
                   help="element size [mm] (default: 2 x the thinnest wall for order 2, wall/2 for order 1)")
    p.add_argument("--order", type=int, choices=[1, 2], default=2, help="element order (2: curved quadratic)")
    p.set_defaults(func=cmd_mesh)


def cmd_cad(args: argparse.Namespace) -> int:
    geometry = require_cad()
    design = resolve_design(args.design)
    out = Path(args.output)
    t0 = time.perf_counter()
    cad = geometry.build_cad(design)
    written = [cad.export_step(out / "rod.step"), cad.export_stl(out / "rod.stl"), cad.write_mass_json(out / "mass.json")]
    if not args.no_png:
        written += geometry.render_views(cad, out, prefix="view", renderer=args.renderer)
    total = cad.total_mass_properties()
    print(f"rod {design.name}: {len(cad.solids)} parts, mass {total.mass_kg * 1e3:.2f} g, COM in {{T}} "
          f"[{', '.join(f'{round(v, 2) + 0.0:.2f}' for v in total.com_T_mm)}] mm ({time.perf_counter() - t0:.1f} s)")
    for p in written:
        print(f"  wrote {p}")
    write_command_report(args, written, out)
    return 0


def cmd_mesh(args: argparse.Namespace) -> int:
    geometry = require_mesher()
    design = resolve_design(args.design)
    t0 = time.perf_counter()
    rm = geometry.mesh_rod(design, size_mm=args.size, order=args.order, msh_path=args.output)
    s = rm.stats
    print(f"rod {design.name}: {s['elements']} tet{10 if rm.order == 2 else 4} elements, {s['nodes']} nodes, "
          f"size {s['size_mm']:g} mm, worst quality (minSICN) {s['min_quality_sicn']:.3f} "
          f"({time.perf_counter() - t0:.1f} s)")
    print(f"  parts: {', '.join(str(p) for p in rm.parts)}; surfaces: flange_face, ball")
    print(f"  wrote {args.output}")
    return 0
