"""A rod's compliance given as a file or a built-in design's name, as every command that takes a rod accepts."""
from __future__ import annotations

from pathlib import Path

__all__ = ["compliance_arg", "DESIGN_HELP"]

#: help of a design argument (info, compliance)
DESIGN_HELP = "a *.rod.toml file, or a built-in design: rod1 .. rod6 (the paper's rods 1# .. 6#)"


def compliance_arg(spec: str):
    """``*.compliance.json`` (read as it is), or a design (``rod1``, ``1#``, ``my.rod.toml``): its closed-form
    (calc) compliance. A file wins over a built-in name only when it is a file."""
    from rodlab.compliance import read_compliance
    from rodlab.design_io import builtin_designs
    p = Path(spec)
    names = builtin_designs()
    alias = {f"{k[3:]}#": k for k in names if k.startswith("rod")}
    key = alias.get(str(spec).strip(), str(spec).strip())
    design = key in names and not p.is_file()
    if design or (p.is_file() and str(spec).lower().endswith(".toml")):
        from rodlab.calc import calc_rod_compliance
        from rodlab.design_io import resolve_design
        print(f"{spec}: the design's closed-form (calc) compliance")
        return calc_rod_compliance(resolve_design(spec))
    return read_compliance(spec)
