"""An answer template that an ``ascii_regex`` instrument's pattern accepts, for its simulator (``rodlab rig
simulator``): the pattern is parsed with Python's own regular-expression parser and walked to its shortest
matching text (a repeat its fewest times, an alternation its first branch, a class its first member), each named
group becoming a number field ``{name:FORMAT}`` in the first format the pattern accepts (a checked line's ``body``
group is walked as its contents, its ``cs`` group is the field ``{cs}``, filled by the simulator). The text is checked
against the pattern before it is used. A new-user trial's ``^G1\\s+(?P<pos>...)\\s*(mm|MM)$`` had been answered
``G1s+-0.05670s*(mm|MM)`` by the character-wise template it replaced, and acquisition then blamed the cable.
"""
from __future__ import annotations

import re

try:                                            # Python 3.11+
    import re._constants as _c
    import re._parser as _p
except ImportError:                             # pragma: no cover - Python 3.10
    import sre_constants as _c
    import sre_parse as _p

from .drivers.ascii_regex import CHECKED_GROUPS
from .errors import RigError

__all__ = ["template_of", "NUMBER_FORMATS"]

#: formats tried for a named group, in order; every one must match -1.23456, 0.5 and 12.5
NUMBER_FORMATS = ("+.5f", ".5f", "+.4f", ".4f", "+.6f", ".6f", "+.3f", ".3f", "+.5e", ".5e", "g")
_PROBES = (-1.23456, 0.5, 12.5)


def template_of(pattern: str, key: str = "pattern") -> str:
    """A ``str.format`` template whose every rendering with numbers in its named fields matches ``pattern``;
    :class:`~.errors.RigError` (``key``) naming the pattern when none can be made."""
    try:
        parsed = _p.parse(pattern)
    except re.error as e:
        raise RigError(f"pattern {pattern!r} is not a regular expression: {e}", key=key) from e
    names = {index: name for name, index in parsed.state.groupdict.items() if name != "body"}
    regex = re.compile(pattern)
    for fmt in NUMBER_FORMATS:
        template = _walk(parsed, names, fmt)
        if template is not None and all(_accepts(regex, template, v) for v in _PROBES):
            return template
    raise RigError(f"the simulator cannot answer in the form of pattern {pattern!r}: no shortest text with numbers "
                   f"in its named groups ({', '.join(names.values()) or 'none'}) matches it; give the group a number "
                   "pattern such as [-+0-9.]+ (the instrument itself is unaffected)", key=key)


def _accepts(regex, template: str, value: float) -> bool:
    fields = {name: value for name in regex.groupindex if name not in CHECKED_GROUPS}
    text = template.format(**fields, cs="00")
    m = regex.search(text.strip())
    return m is not None and all(abs(float(m.group(n)) - value) <= 1e-3 * max(1.0, abs(value)) for n in fields)


def _walk(items, names: dict, fmt: str) -> str | None:
    out = []
    for op, av in items:
        piece = _token(op, av, names, fmt)
        if piece is None:
            return None
        out.append(piece)
    return "".join(out)


def _token(op, av, names: dict, fmt: str) -> str | None:
    """The shortest text of one parsed token (None where it cannot be written down, e.g. a back-reference)."""
    if op is _c.LITERAL:
        return _literal(chr(av))
    if op is _c.NOT_LITERAL:
        return "x" if chr(av) != "x" else "y"
    if op is _c.ANY:
        return "x"
    if op is _c.IN:
        return _member(av)
    if op in (_c.MAX_REPEAT, _c.MIN_REPEAT) or op is getattr(_c, "POSSESSIVE_REPEAT", None):
        lo, _, sub = av
        one = _walk(sub, names, fmt)
        return None if one is None else one * lo
    if op is _c.SUBPATTERN:
        group, sub = av[0], av[-1]
        if group in names:
            return "{cs}" if names[group] == "cs" else "{" + names[group] + ":" + fmt + "}"
        return _walk(sub, names, fmt)
    if op is getattr(_c, "ATOMIC_GROUP", None):
        return _walk(av, names, fmt)
    if op is _c.BRANCH:
        return _walk(av[1][0], names, fmt)
    if op in (_c.AT, _c.ASSERT, _c.ASSERT_NOT):
        return ""
    return None


def _member(items) -> str | None:
    """The first character a character class ``[...]`` accepts."""
    if any(op is _c.NEGATE for op, _ in items):
        return next((_literal(c) for c in "xay0 ;" if not _in_class(items, c)), None)
    op, av = items[0]
    if op is _c.LITERAL:
        return _literal(chr(av))
    if op is _c.RANGE:
        return _literal(chr(av[0]))
    if op is _c.CATEGORY:
        return {_c.CATEGORY_DIGIT: "0", _c.CATEGORY_SPACE: " ", _c.CATEGORY_WORD: "a"}.get(av, "x")
    return None


def _in_class(items, ch: str) -> bool:
    code = ord(ch)
    for op, av in items:
        if op is _c.LITERAL and av == code:
            return True
        if op is _c.RANGE and av[0] <= code <= av[1]:
            return True
        if op is _c.CATEGORY and re.match({_c.CATEGORY_DIGIT: r"\d", _c.CATEGORY_SPACE: r"\s",
                                           _c.CATEGORY_WORD: r"\w"}.get(av, r"(?!)"), ch):
            return True
    return False


def _literal(ch: str) -> str:
    return ch.replace("{", "{{").replace("}", "}}")
