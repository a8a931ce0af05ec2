"""``rodlab info``: inspect a design (parts, mass properties, closed-form compliance)."""
from __future__ import annotations

import argparse
import json

import numpy as np

from ...core.calc import calc_rod_compliance
from ...core.compliance import DEFAULT_CONTACT_FORCE_N
from ...core.design_io import resolve_design
from ...core.massprops import mass_properties, part_mass_properties
from ...core.units import PAPER_C_ROD_UM_RANGE
from .rodargs import design_help

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("info", help="print a rod design, its parts, mass, centre of mass and c_rod",
                       description="Print a rod design: parts, mass properties (analytic) and the closed-form "
                                   "compliance with c_rod (paper Eq. 23).")
    p.add_argument("design", help=design_help(paper=True))
    p.add_argument("--json", action="store_true", help="print machine-readable JSON instead of text")
    p.set_defaults(func=cmd_info)


def _fmt_matrix(a: np.ndarray, unit: str) -> str:
    rows = ["  [" + "  ".join(f"{v:+.6f}" for v in row) + "]" for row in a]
    return "\n".join(rows) + f"   {unit}"


def cmd_info(args: argparse.Namespace) -> int:
    design = resolve_design(args.design)
    parts = part_mass_properties(design)
    total = mass_properties(design)
    comp = calc_rod_compliance(design)
    if args.json:
        out = {"design": design.summary(), "tool_mm": design.tool_mm.tolist(),
               "parts": {str(p): m.to_dict() for p, m in parts.items()}, "total": total.to_dict(),
               "calc": comp.to_dict(),
               "materials": {m.name: _material_dict(m) for m in (design.material_of(p) for p in parts)}}
        print(json.dumps(out, indent=1))
        return 0
    s = design.summary()
    print(f"rod {design.name}" + (f"  ({design.source})" if design.source else ""))
    print(f"  L1 = {design.L1_mm:g} mm, L2 = {design.L2_mm:g} mm, gamma = {design.gamma_deg:g} deg; "
          f"tool point in {{6}} = [{', '.join(f'{v:.3f}' for v in design.tool_mm)}] mm")
    print(f"  {'part':<12} {'material':<12} {'OD mm':>7} {'wall/len mm':>11} {'mass g':>9}  COM in {{T}} mm")
    rows = {"pipe_I": s["pipe_I"], "pipe_II": s["pipe_II"], "bend": s["bend"], "ring_1": s["rings"],
            "ring_2": s["rings"], "pipe_holder": s["pipe_holder"], "ball_holder": s["ball_holder"],
            "ball": s["ball"]}
    for part, mp in parts.items():
        info = rows[str(part)]
        size = info.get("wall_mm", info.get("length_mm", ""))
        od = info.get("outer_diameter_mm", info.get("diameter_mm"))
        com = ", ".join(f"{round(v, 2) + 0.0:8.2f}" for v in mp.com_T_mm)
        print(f"  {str(part):<12} {info['material']:<12} {od:>7g} {size!s:>11} {1e3 * mp.mass_kg:>9.2f}  [{com}]")
    print(f"  total mass {total.mass_kg * 1e3:.2f} g, COM in {{T}} = "
          f"[{', '.join(f'{round(v, 2) + 0.0:.2f}' for v in total.com_T_mm)}] mm")
    _print_materials(design, parts)
    for place, spring in design.joints.items():       # rodlab.rod/2: in series in every compliance below
        print(f"  declared joint at {place}: s_bend {spring.s_bend_rad_per_Nm:g}, s_torsion "
              f"{spring.s_torsion_rad_per_Nm:g} rad/(N m) (included in the compliance)")
    print("  closed-form C_F (force on ball -> ball displacement, {T}):")
    print(_fmt_matrix(comp.C_F, "mm/N"))
    print("  closed-form C_g (gravity in {T} -> ball displacement):")
    print(_fmt_matrix(comp.C_g, "mm/g0"))
    print(f"  c_rod (Eq. 23) = {comp.c_rod_um:.1f} um (sum of C_g + sum of C_F x |F|, F the paper's contact force "
          f"[1.10, 1.25, 1.05] N: |F| = {np.linalg.norm(DEFAULT_CONTACT_FORCE_N):.2f} N; closed form, on average "
          f"6-17 % stiffer than the solid FEA entry by entry, up to ~25 %: `rodlab fea` (frame, ~1 %) for numbers to "
          f"build on)")
    from rodlab.fea import closed_form_notes
    for note in closed_form_notes(design, comp) + _c_rod_notes(comp.c_rod_um):
        print(f"  note: {note}")
    return 0


def _material_dict(m) -> dict:
    """A material's numbers for ``info --json`` (derived G and E_t included)."""
    return {"E_GPa": m.E_GPa, "E_transverse_GPa": m.E_t_GPa, "G_GPa": m.G_axial_GPa, "nu": m.nu,
            "density_kg_m3": m.density_kg_m3, "cte_ppm_K": m.cte_ppm_K, "strength_MPa": m.strength_MPa,
            "source": m.source}


def _print_materials(design, parts) -> None:
    """The numbers each material of the design carries (a designer trial: a built-in laminate's moduli, density
    and expansion were shown nowhere, so the design could not be checked by hand)."""
    mats = {}
    for part in parts:
        m = design.material_of(part)
        mats.setdefault(m.name, m)
    print(f"  {'material':<12} {'E GPa':>7} {'E_t GPa':>8} {'G GPa':>7} {'nu':>5} {'kg/m^3':>7} {'ppm/K':>6} "
          f"{'MPa':>6}  source")
    for m in mats.values():
        print(f"  {m.name:<12} {m.E_GPa:>7.4g} {m.E_t_GPa:>8.4g} {m.G_axial_GPa:>7.4g} {m.nu:>5.3g} "
              f"{m.density_kg_m3:>7.0f} {_cell(m.cte_ppm_K, '.3g'):>6} {_cell(m.strength_MPa, '.0f'):>6}  "
              f"{m.source or '-'}")


def _cell(v, fmt: str) -> str:
    """``v`` in ``fmt``, or ``-`` where the material does not give it."""
    return "-" if v is None else format(v, fmt)


def _c_rod_notes(c_rod_um: float) -> list[str]:
    """A c_rod (here the closed form's) beyond the paper's measured rods (57.9 um carbon 1# to 1306.2 um steel 6#):
    named, with what makes a rod that soft (a paper trial: the contract's example tube, `cfrp` 25 x 2, gives
    1500-1700 um)."""
    lo, hi = PAPER_C_ROD_UM_RANGE
    if c_rod_um <= hi:
        return []
    return [f"c_rod {c_rod_um:.0f} um (closed form) is softer than every rod the paper measured ({lo:g} um carbon 1# "
            f"to {hi:g} um steel 6#): check the tube's size and material (a carbon laminate's E and G: "
            "docs/formats.md); `rodlab study` predicts what such a rod gives on a robot"]
