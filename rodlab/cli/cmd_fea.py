"""``rodlab fea``: compliance of a design by the solid FEA, the frame model or the closed form."""
from __future__ import annotations

import argparse
import time

import numpy as np

from ..compliance import write_compliance
from ..design_io import resolve_design
from ..errors import RodlabError

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("fea", help="compute C_F and C_g by solid FEA (reference), beam frame or closed form",
                       description="Compute the compliance file of a rod design. solid: 3-D elasticity on the CAD "
                                   "mesh (scikit-fem, curved P2, transversely-isotropic carbon; needs the cad "
                                   "extra); frame: Timoshenko beam frame with pipe-bend flexibility (fast); "
                                   "calc: the closed form.")
    p.add_argument("design", help="a *.rod.toml file, or a built-in design: rod1 .. rod6")
    p.add_argument("-o", "--output", required=True, help="output *.compliance.json")
    p.add_argument("--model", choices=["solid", "frame", "calc"], default="solid")
    p.add_argument("--size", type=float, default=None, help="solid: element size far from the section changes "
                   "[mm] (default 3 x the thinnest wall; inside the tubes graded down to 0.9 x wall at the section "
                   "changes, at most 2.1 x wall in the bend)")
    p.add_argument("--no-error-estimate", action="store_true",
                   help="solid: skip the second (coarser) solve for the Richardson error estimate")
    p.add_argument("--no-symmetry", action="store_true",
                   help="solid: mesh and solve the whole rod instead of the half y_T >= 0 (same result, ~2x slower)")
    p.add_argument("--png", default=None, help="solid: write the deformed shape (self-weight along -z_T) to this PNG")
    p.set_defaults(func=cmd_fea)


def cmd_fea(args: argparse.Namespace) -> int:
    from fea import FeaModel, compute_compliance, solid_compliance
    design = resolve_design(args.design)
    t0 = time.perf_counter()
    if args.model == FeaModel.SOLID.value:
        from .cmd_geometry import require_cad
        geometry = require_cad()

        def mesher(d, h, grading, half):
            return geometry.mesh_rod(d, size_mm=h, grading=grading, half=half)
        comp, res = solid_compliance(design, mesher, size_mm=args.size, error_estimate=not args.no_error_estimate,
                                     keep_displacements=bool(args.png), symmetry=not args.no_symmetry)
        prov = comp.provenance
        print(f"solid FEA of rod {design.name}: {prov['dofs']} DOFs ({prov['mesh']['elements']} curved tet10"
              f"{', half model' if res.rod_mesh.is_half else ''}), "
              f"solver {prov['solver']}, symmetry defect of C_F {prov['symmetry_defect_C_F']:.1e}")
        if "discretisation_error" in prov:
            e = prov["discretisation_error"]
            print(f"  estimated discretisation error: {100 * e['max_relative_C_F']:.3f} % of max|C_F|, "
                  f"{100 * e['max_relative_C_g']:.3f} % of max|C_g|")
        if args.png:
            from fea.plot import render_deformed
            U = res.displacements.copy()
            U[:, 5] *= -1.0                                     # gravity along -z_T, as on a vertical flange
            out = render_deformed(res.rod_mesh, U, args.png, case=5,
                                  title=f"rod {design.name}: self-weight, gravity along -z_T",
                                  load_label="self-weight, 1 g0 along -z_T")
            print(f"  wrote {out}")
    else:
        if args.png or args.size is not None or args.no_symmetry:
            raise RodlabError("--png, --size and --no-symmetry apply to --model solid only")
        comp = compute_compliance(design, args.model)
        for note in comp.provenance.get("outside_calibrated_range") or []:
            print(f"  note: {note}; check this design with --model solid, or calibrate the frame on it "
                  "(rodlab sweep --calibrate)")
    path = write_compliance(comp, args.output)
    np.set_printoptions(precision=6, suppress=True)
    print(f"  C_F [mm/N] =\n{comp.C_F}\n  C_g [mm/g0] =\n{comp.C_g}")
    print(f"  c_rod = {comp.c_rod_um:.1f} um ({time.perf_counter() - t0:.1f} s); wrote {path}")
    return 0
