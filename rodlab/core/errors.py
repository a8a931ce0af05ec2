"""Exception hierarchy of the rodlab core.

Every error a user can trigger with bad input derives from :class:`RodlabError`, a
:class:`ValueError`; the CLI catches it and prints its message (never a traceback).
Domain packages (geometry, fea, stiffness_rig, calibrate) subclass it with their own base.
Messages name the file, the line or key, what was expected and what was found, and
suggest the fix where one is obvious ("Did you mean `wall_mm`?").
"""
from __future__ import annotations

import difflib
import re
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
    "expect_type",
    "first_reasons",
]


#: unit families: the factor from each unit to the family's others is the ratio of their sizes (in the first unit
#: of the family); a hint is given only between two units of one family (no temperatures: their offsets)
_UNIT_SIZES = ({"mm": 1.0, "um": 1e-3, "nm": 1e-6, "m": 1e3, "cm": 10.0, "in": 25.4},
               {"kg": 1.0, "g": 1e-3, "lb": 0.45359237},
               {"N": 1.0, "kN": 1e3, "mN": 1e-3, "lbf": 4.4482216152605},
               {"GPa": 1.0, "MPa": 1e-3, "Pa": 1e-9},
               {"s": 1.0, "ms": 1e-3, "min": 60.0},
               {"rad": 1.0, "deg": 0.017453292519943295})


def _family(unit: str) -> dict | None:
    return next((f for f in _UNIT_SIZES if unit in f), None)


def _other_unit(word: str, choices: list[str]) -> str:
    """`` `x_um` is `x_mm` in another unit ...`` when ``word`` is one of ``choices`` with another unit of the same
    kind as its last suffix (not a compound unit: ``_per_`` names are left alone)."""
    stem, _, unit = word.rpartition("_")
    family = _family(unit)
    if not stem or family is None or "_per" in f"_{stem}":
        return ""
    for c in choices:
        c_stem, _, c_unit = c.rpartition("_")
        if c_stem.casefold() == stem.casefold() and c_unit != unit and c_unit in family:
            factor = family[unit] / family[c_unit]
            return (f" `{word}` is `{c}` in another unit: rodlab reads {c_unit} there, so multiply the values by "
                    f"{factor:g} as you rename the column (a rename alone would read them as {c_unit}).")
    return ""


#: a controller's names of joint k's column (J1, A1, axis_1, joint1, q_1, J1_deg): the contract's q<k>
_JOINT_ALIAS = re.compile(r"(?:j|a|ax|axis|joint|q|achse|gelenk|axe)[ _]?([0-9][0-9]?)(?:[ _]?(?:deg|\(deg\)|\[deg\]))?",
                          re.IGNORECASE)


def joint_alias_number(word: str) -> int | None:
    """The joint number a controller's column name gives (``J1``, ``A1``, ``axis_1``, ``Achse1``: 1; ``J0``: 0), or
    None."""
    m = _JOINT_ALIAS.fullmatch(str(word))
    return int(m.group(1)) if m else None
#: a name with its unit in brackets (``X [mm]``, ``x (mm)``): the contract writes ``x_mm``
_BRACKET_UNIT = re.compile(r"(.+?)\s*[\[(]\s*(\w+)\s*[\])]")


def first_reasons(reasons, k: int = 3) -> str:
    """The first ``k`` of ``reasons`` joined by '; ', and how many more there are."""
    reasons = list(reasons)
    more = f"; and {len(reasons) - k} more reasons" if len(reasons) > k else ""
    return "; ".join(reasons[:k]) + more


def did_you_mean(word: str, choices: Iterable[str], units: bool = False) -> str:
    """Return `` Did you mean `x`?`` for the closest of ``choices``, or ``""``. ``units``: ``word`` is the user's
    name and ``choices`` the expected ones (a table's columns): a name with another unit of the same kind than one
    of them (``disp_x_um`` for ``disp_x_mm``) is told what to convert as well."""
    word, choices = str(word), [str(c) for c in choices]
    unit = _other_unit(word, choices) if units else ""
    if unit:
        return unit
    joint = _JOINT_ALIAS.fullmatch(word)
    listed = {c for c in choices if re.fullmatch(r"q[0-9]+", c)}          # the joints' columns, or q1 for the pattern
    k = int(joint.group(1)) if joint else 0
    if joint and "q1" in choices and word != f"q{k}" and (f"q{k}" in listed or listed == {"q1"}):
        return (f" Did you mean `q{k}`? (the joint angles are the columns q1, q2, ... in degrees: "
                "rename each joint's column)")
    bracket = _BRACKET_UNIT.fullmatch(word)
    named = f"{bracket.group(1).strip().lower()}_{bracket.group(2).lower()}" if bracket else ""
    if named in choices:
        return f" Did you mean `{named}`? (the unit goes after an underscore)"
    folded = [c for c in choices if c.casefold() == word.casefold()]
    # a key given without its unit suffix (``L1`` for ``L1_mm``, ``hold`` for ``hold_s``)
    stem = [c for c in choices if c.casefold().startswith(word.casefold() + "_")] if word else []
    close = (folded or (stem if len(stem) == 1 else [])
             or [c for c in difflib.get_close_matches(word, choices, n=3, cutoff=0.6) if _alike(word, c)])
    return f" Did you mean `{close[0]}`?" if close else ""


def _alike(word: str, choice: str) -> bool:
    """A typo keeps the first letter, a shortened name one of the words (``axis`` for ``load_axis``); another word
    is suggested only when much alike (a trial's German ``Achse`` had been offered ``phase``)."""
    w, c = word.casefold(), choice.casefold()
    same_start = w[:1] == c[:1]
    return same_start or w in c.split("_") or difflib.SequenceMatcher(None, w, c).ratio() >= 0.75


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


def expect_type(value, cls, name: str, fix: str) -> None:
    """Raise :class:`TypeError` naming the argument ``name``, the type expected and given, and ``fix`` (how to make one),
    unless ``value`` is a ``cls`` (a library call given a name where an object is expected fails here, not deep
    inside: ``calc_compliance("rod1")``)."""
    if not isinstance(value, cls):
        raise TypeError(f"{name}: expected a {cls.__name__}, got {type(value).__name__} {value!r:.60}; {fix}")
