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


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """Return `` Did you mean `x`?`` for the closest of ``choices``, or ``""``."""
    word, choices = str(word), [str(c) for c in choices]
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
