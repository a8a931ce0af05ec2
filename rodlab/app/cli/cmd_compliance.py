"""``rodlab compliance``: a rod's compliance file by the closed form."""
from __future__ import annotations

import argparse
from dataclasses import replace

from ...core.calc import BendModel, calc_rod_compliance
from ...core.compliance import RodCompliance, write_compliance
from ...core.design_io import resolve_design
from ...core.enums import Method
from .reporting import add_report_option, write_command_report
from .rodargs import design_help

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("compliance", help="compute a rod's compliance file (closed form)",
                       description="Compute C_F and C_g of a rod design and write a *.compliance.json "
                                   "(contract rodlab.compliance/1). For finite elements use `rodlab fea`.")
    p.add_argument("design", help=design_help(paper=True))
    p.add_argument("--method", choices=["calc", "none"], default="calc",
                   help="calc: closed-form Euler-Bernoulli frame (paper Eqs. 15/17 generalised); "
                        "none: zero matrices (no compensation)")
    p.add_argument("--bend", choices=[m.value for m in BendModel], default="arc",
                   help="bend model of the closed form: arc (curved beam) or corner (sharp-corner idealisation)")
    p.add_argument("--shear", action="store_true", help="add Timoshenko shear flexibility")
    p.add_argument("-o", "--output", help="output file (default: NAME.compliance.json in the current folder)")
    add_report_option(p)
    p.set_defaults(func=cmd_compliance)


def _closed_form_notes(design, comp) -> list[str]:
    """:func:`rodlab.fea.closed_form_notes` for the default closed form (another bend model or shear setting is
    the user's choice, compared as it is)."""
    from rodlab.fea import closed_form_notes
    return closed_form_notes(design, comp)


def cmd_compliance(args: argparse.Namespace) -> int:
    design = resolve_design(args.design)
    comp = calc_rod_compliance(design, bend=BendModel(args.bend), shear=args.shear)
    if args.method == Method.NONE.value:
        comp = RodCompliance.none_like(comp)
    out = args.output or f"{design.name.replace('#', '')}.compliance.json"
    if not args.output and not out[0].isalpha():
        out = f"rod{out}"
    notes = _closed_form_notes(design, comp) if args.method != Method.NONE.value else []
    if notes:
        comp = replace(comp, provenance=dict(comp.provenance, notes=notes))
    path = write_compliance(comp, out)
    print(f"wrote {path}: method {comp.method}, c_rod = {comp.c_rod_um:.1f} um, mass = {comp.mass_kg * 1e3:.1f} g")
    for note in notes:
        print(f"  note: {note}")
    write_command_report(args, [path], path.parent)
    return 0
