"""Exception hierarchy of the rodlab core.

Every error a user can trigger with bad input derives from :class:`RodlabError`, a
:class:`ValueError`; the CLI catches it and prints its message (never a traceback).
Domain packages (geometry, fea, stiffness_rig, calibrate) subclass it with their own base.
Messages name the file, the line or key, what was expected and what was found, and
suggest the fix where one is obvious ("Did you mean `wall_mm`?").
"""
from __future__ import annotations

import difflib
from collections.abc import Iterable
from pathlib import Path

__all__ = [
    "RodlabError",
    "LocatedError",
    "VerdictError",
    "RenderError",
    "FormatError",
    "DesignError",
    "ComplianceError",
    "did_you_mean",
]


#: factors from a unit a name may carry to the unit rodlab's name for that quantity carries (value x factor)
_UNIT_FACTORS = {("um", "mm"): 1e-3, ("m", "mm"): 1e3, ("cm", "mm"): 10.0, ("in", "mm"): 25.4, ("g", "kg"): 1e-3,
                 ("lb", "kg"): 0.45359237, ("kN", "N"): 1e3, ("mN", "N"): 1e-3, ("MPa", "GPa"): 1e-3,
                 ("Pa", "GPa"): 1e-9, ("ms", "s"): 1e-3, ("min", "s"): 60.0, ("deg", "rad"): 0.017453292519943295,
                 ("rad", "deg"): 57.29577951308232}


#: unit suffixes a name may end in (the others are not units: ``upper_arm_lnk`` is a typo of ``upper_arm_link``)
_UNITS = {u for pair in _UNIT_FACTORS for u in pair} | {"nm", "lbf", "N", "Nm", "Nmm", "C", "F", "K", "Hz", "g0"}


def _other_unit(word: str, choices: list[str]) -> str:
    """`` `x_um` is `x_mm` in another unit ...`` when ``word`` is one of ``choices`` with another unit suffix."""
    stem, _, unit = word.rpartition("_")
    if not stem or unit not in _UNITS:
        return ""
    for c in choices:
        c_stem, _, c_unit = c.rpartition("_")
        if c_stem.casefold() == stem.casefold() and c_unit in _UNITS and c_unit != unit:
            factor = _UNIT_FACTORS.get((unit, c_unit))
            how = f"multiply the values by {factor:g}" if factor else f"convert the values from {unit} to {c_unit}"
            return (f" `{word}` is `{c}` in another unit: rodlab reads {c_unit} there, so {how} as you rename the "
                    f"column (a rename alone would read them as {c_unit}).")
    return ""


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return `` Did you mean `x`?`` for the closest of ``choices``, or ``""``; for a name with another unit
    suffix than one of ``choices`` (``disp_x_um`` for ``disp_x_mm``) what to convert as well."""
    word, choices = str(word), [str(c) for c in choices]
    unit = _other_unit(word, choices)
    if unit:
        return unit
    folded = [c for c in choices if c.casefold() == word.casefold()]
    # a key given without its unit suffix (``L1`` for ``L1_mm``, ``hold`` for ``hold_s``)
    stem = [c for c in choices if c.casefold().startswith(word.casefold() + "_")] if word else []
    close = folded or (stem if len(stem) == 1 else []) or difflib.get_close_matches(word, choices, n=1, cutoff=0.6)
    return f" Did you mean `{close[0]}`?" if close else ""


class RodlabError(ValueError):
    """Base of every rodlab error caused by input (files, parameters, designs)."""


class VerdictError(RodlabError):
    """Good input whose content refuses the result (a design update the freed keys cannot fit, a recording whose
    diagnosis names a cause not freed): the CLI exits 3, as for a NOT TRUSTED calibration; bad input exits 2."""


class RenderError(RodlabError):
    """3-D rendering impossible here (no pyvista, no OpenGL), or a field file it cannot show."""


class LocatedError(RodlabError):
    """An error that says where: the file, line and key (or parameter) at fault, each where known.

    Attributes
    ----------
    path : the offending file (or ``None`` for in-memory data)
    line : 1-based line number where known
    key : the offending key / column where known
    detail : the message without the location prefix
    also : further problems found in the same pass (a design's rules are all checked: ``rodlab validate`` lists
        each), shown after this one's message
    """

    def __init__(self, message: str, path: str | Path | None = None,
                 line: int | None = None, key: str | None = None, also: Iterable[LocatedError] = ()) -> None:
        self.path = None if path is None else str(path)
        self.detail = message
        self.line = line
        self.key = key
        self.also = tuple(also)
        where = []
        if self.path is not None:
            where.append(self.path)
        if line is not None:
            where.append(f"line {line}")
        if key is not None:
            where.append(f"key `{key}`")
        prefix = ", ".join(where)
        more = "".join(f"\n  and: {a}" for a in self.also)
        super().__init__((f"{prefix}: {message}" if prefix else message) + more)


class FormatError(LocatedError):
    """A file does not follow its contract format (names the file, line and key)."""


class DesignError(FormatError):
    """A rod design is invalid: a rule of the design is broken (names the key and rule)."""


class ComplianceError(FormatError):
    """A compliance file or compliance matrix is invalid."""
