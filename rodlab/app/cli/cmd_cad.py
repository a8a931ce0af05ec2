"""``rodlab cad``: the CAD assembly of a design: STEP, STL, PNG views, mass.json (``cad`` extra)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from ...core.design_io import resolve_design
from ...core.progress import stages
from .cadextra import require_cad
from .reporting import add_report_option, write_command_report
from .rodargs import design_help

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("cad", help="build the CAD assembly: STEP, STL, PNG views, mass.json",
                       description="Build the rod as a multi-part CAD assembly (build123d) in the tool frame {T}; "
                                   "write DIR/rod.step (part names and colours), DIR/rod.stl, PNG views (iso, xz, "
                                   "xy, yz) and DIR/mass.json (per part and total: mass, COM in {T}, inertia).")
    p.add_argument("design", help=design_help())
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.add_argument("--no-png", action="store_true", help="skip the PNG views")
    p.add_argument("--renderer", choices=["auto", "pyvista", "matplotlib"], default="auto",
                   help="PNG views: pyvista (viz extra; the renderer of rodlab view), matplotlib (anywhere), or "
                        "auto: pyvista where it renders off-screen (default)")
    add_report_option(p)
    p.set_defaults(func=cmd_cad)


def cmd_cad(args: argparse.Namespace) -> int:
    design = resolve_design(args.design)
    out = Path(args.output)
    t0 = time.perf_counter()
    steps = ["build123d", "assembly", "STEP", "STL", "mass"] + ([] if args.no_png else ["views"])
    with stages(f"CAD of {design.name}", steps) as bar:        # 6-12 s in all: the import is 2-3 s of it
        with bar.step("build123d"):
            geometry = require_cad()
        with bar.step("assembly"):
            cad = geometry.build_cad(design)
        with bar.step("STEP"):
            written = [cad.export_step(out / "rod.step")]
        with bar.step("STL"):
            written.append(cad.export_stl(out / "rod.stl"))
        with bar.step("mass"):
            written.append(cad.write_mass_json(out / "mass.json"))
        if not args.no_png:
            with bar.step("views"):
                written += geometry.render_views(cad, out, prefix="view", renderer=args.renderer)
    total = cad.total_mass_properties()
    print(f"rod {design.name}: {len(cad.solids)} parts, mass {total.mass_kg * 1e3:.2f} g, COM in {{T}} "
          f"[{', '.join(f'{round(v, 2) + 0.0:.2f}' for v in total.com_T_mm)}] mm ({time.perf_counter() - t0:.1f} s)")
    for p in written:
        print(f"  wrote {p}")
    write_command_report(args, written, out)
    return 0
