"""A rod's compliance given as a file or a built-in design's name, as every command that takes a rod accepts."""
from __future__ import annotations

import re
import sys
from pathlib import Path

from ...core.calc import calc_rod_compliance
from ...core.compliance import read_compliance
from ...core.design_io import builtin_designs, resolve_design
from ...core.errors import RodlabError

__all__ = ["compliance_arg", "design_help", "builtin_designs_text", "same_rod", "warn_rod_mismatch",
           "design_of_compliance"]


def builtin_designs_text() -> str:
    """The built-in designs for a help text: ``rod1 .. rod6`` when they are numbered without a gap, else each."""
    names = sorted(builtin_designs(), key=lambda n: (len(n), n))
    numbers = [re.fullmatch(r"rod([0-9]+)", n) for n in names]
    if len(names) > 2 and all(numbers) and [int(m.group(1)) for m in numbers] == list(
            range(int(numbers[0].group(1)), int(numbers[0].group(1)) + len(names))):
        return f"{names[0]} .. {names[-1]}"
    return ", ".join(names)


def design_help(paper: bool = False) -> str:
    """Help of a design argument, the built-in designs from the package's data (``paper``: say they are the
    paper's rods)."""
    return (f"a *.rod.toml file, or a built-in design: {builtin_designs_text()}"
            + (" (the paper's rods 1# .. 6#)" if paper else ""))


def compliance_arg(spec: str, slips_refused: bool = False):
    """``*.compliance.json`` (read as it is), or a design (``rod1``, ``1#``, ``my.rod.toml``): its closed-form
    (calc) compliance. A file wins over a built-in name only when it is a file. ``slips_refused``: the caller refuses a
    unit slip itself (:func:`~.deviceargs.refuse_rod_slips`), so the reader does not warn of it first."""
    p = Path(spec)
    names = builtin_designs()
    alias = {f"{k[3:]}#": k for k in names if k.startswith("rod")}
    key = alias.get(str(spec).strip(), str(spec).strip())
    design = key in names and not p.is_file()
    if design or (p.is_file() and str(spec).lower().endswith(".toml")):
        print(f"{spec}: the design's closed-form (calc) compliance")
        return calc_rod_compliance(resolve_design(spec))
    if not p.exists():
        raise RodlabError(f"{spec}: no such file, and not a built-in design. Give a *.compliance.json (rodlab fea "
                          f"DESIGN -o FILE makes one), or a design ({', '.join(sorted(names))}, or a *.rod.toml) for "
                          f"its closed-form (calc) compliance")
    return read_compliance(spec, warn_unit_slips=not slips_refused)


def same_rod(a: str, b: str) -> bool:
    """Whether two rod names are one rod (``rod1``, ``1#``, ``Rod 1`` and ``rod_1`` are)."""
    return _rod_key(a) == _rod_key(b)


def _rod_key(name: str) -> str:
    """A rod's name for comparing: ``rod1``, ``1#``, ``Rod 1`` and ``rod_1`` are one rod."""
    return re.sub(r"[\s#_\-]|^rod", "", str(name).strip().lower())


def warn_rod_mismatch(recording_rod: str | None, rod: str | None, source: str, option: str = "--sim",
                      against: str = "the simulation", named_by: str = " (its '# rod:' line)") -> bool:
    """Warn (stderr) when a recording's ``# rod:`` (or a measured file's rod, ``named_by``) names another rod than
    ``rod``, the rod of the simulation (or the design, ``against``): the comparison would then measure the
    difference between two rods, not this rod's physics. Returns whether it warned."""
    if not recording_rod or not rod or same_rod(recording_rod, rod):
        return False
    what = "this rod's compliance" if option == "--sim" else "this rod's measurement"
    print(f"warning: {source} is of rod {recording_rod!r}{named_by} and {against} of rod {rod!r}: "
          f"check that {option} is {what}", file=sys.stderr)
    return True


def design_of_compliance(comp):
    """The design a compliance file was made from (the design file its provenance names, when that file still
    hashes to it), else the built-in design of its rod's name; None when neither is known."""
    from ..diagnose.envelope import design_of
    found = design_of(comp)
    if found is not None:
        return found
    try:
        return resolve_design(comp.rod)
    except RodlabError:
        return None
