"""``rodlab mesh``: the FEA mesh of a design (gmsh, ``cad`` extra)."""
from __future__ import annotations

import argparse
import time
from pathlib import Path

from ...core.design_io import resolve_design
from ...core.errors import RodlabError
from .argtypes import pos_float
from .cadextra import require_mesher
from .rodargs import design_help

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("mesh", help="mesh the rod for FEA (gmsh, one physical volume per part)",
                       description="Conformal tetrahedral mesh of all parts (bonded interfaces share nodes), "
                                   "physical volumes named after the parts, physical surfaces flange_face and "
                                   "ball; gmsh 4.1 format.")
    p.add_argument("design", help=design_help())
    p.add_argument("-o", "--output", required=True, help="output .msh file")
    p.add_argument("--size", type=pos_float, default=None,
                   help="element size [mm] (default: 2 x the thinnest wall for order 2, wall/2 for order 1)")
    p.add_argument("--order", type=int, choices=[1, 2], default=2, help="element order (2: curved quadratic)")
    p.set_defaults(func=cmd_mesh)


def cmd_mesh(args: argparse.Namespace) -> int:
    if Path(args.output).suffix.lower() != ".msh":
        raise RodlabError(f"-o {args.output}: rodlab mesh writes gmsh's format (4.1): give a name ending in .msh "
                          f"(for VTK fields of the solved rod: rodlab fea DESIGN --model solid --fields OUT.vtu)")
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
