"""``ascii_regex``: a sensor controller's ASCII protocol (Keyence, Ono Sokki, most amplifiers): a request line
and an answer matched by a regular expression whose named groups are the values, e.g. ``request = "M0\\r"``,
``pattern = "^M0,(?P<out1>[-+0-9.]+),(?P<out2>[-+0-9.]+)$"``. Scale and units of each value are the channel's
(the profile). An empty request: the controller pushes its lines. A checked line names the checksummed text
``(?P<body>...)`` and its two hex digits ``(?P<cs>..)``, e.g.
``pattern = "^(?P<body>M0,(?P<out1>[-+0-9.]+))\\*(?P<cs>[0-9A-Fa-f]{2})$"`` with ``checksum = "xor"`` or ``"sum8"``."""
from __future__ import annotations

import math
import re

from rodlab.core.enums import Checksum

from ..protocol import checksum_mismatch
from .base import INIT_SETTING, Driver, Garbage, Link, Setting, SettingError, unescape

__all__ = ["AsciiRegex", "CHECKED_GROUPS"]


class AsciiRegex(Driver):
    name = "ascii_regex"
    summary = "a request line and an answer matched by a regular expression; its named groups are the values"
    settings = (Setting("request", str, "", "what asks for a reading (empty: the controller pushes lines)"),
                Setting("pattern", str, None, "regular expression of one answer line (stripped), a named group "
                                              "(?P<name>...) per value"),
                Setting("eol", str, "\\n", "the character that ends an answer line"),
                Setting("checksum", str, Checksum.NONE.value, "none, xor or sum8 of the pattern's group body, "
                        "compared with its group cs (two hex digits)", tuple(m.value for m in Checksum)),
                INIT_SETTING)
    simulator = "SimAsciiRegex"

    def __init__(self, config: dict) -> None:
        super().__init__(config)
        self.regex = re.compile(config["pattern"])
        self.checksum = str(config.get("checksum", Checksum.NONE.value))
        missing = [g for g in CHECKED_GROUPS if g not in self.regex.groupindex]
        if self.checksum != Checksum.NONE.value and missing:
            raise SettingError("pattern", f"checksum = {self.checksum!r} needs the pattern's groups (?P<body>...) "
                                          f"(the checksummed text) and (?P<cs>..) (its two hex digits); missing: "
                                          f"{', '.join(missing)}, e.g. pattern = "
                                          f"\"^(?P<body>M0,(?P<out1>[-+0-9.]+))\\\\*(?P<cs>[0-9A-Fa-f]{{2}})$\"")

    @property
    def values(self) -> tuple:
        return tuple(g for g in self.regex.groupindex if g not in CHECKED_GROUPS)

    def poll(self, link: Link) -> dict:
        request = unescape(self.config.get("request", ""))
        eol = unescape(self.config.get("eol", "\\n")).encode("ascii")
        if request:
            link.clear_input()
            link.write(request.encode("ascii"))
            raw = link.readline(eol)
        else:
            raw = link.latest_line(eol)
        text = raw.decode("ascii", "replace").strip()
        m = self.regex.search(text)
        if not m:
            raise Garbage(raw, f"the pattern {self.regex.pattern!r} does not match it")
        self._check(raw, m)
        out = {}
        for k in self.values:
            try:
                v = float(m.group(k))
            except (TypeError, ValueError):
                raise Garbage(raw, f"group {k} is not a number") from None
            if not math.isfinite(v):
                raise Garbage(raw, f"group {k} is not finite")
            out[k] = v
        return out

    def _check(self, raw: bytes, m: re.Match) -> None:
        """Garbage where the line's checksum does not match its body's."""
        if self.checksum == Checksum.NONE.value:
            return
        mismatch = checksum_mismatch((m.group("body") or "").encode("ascii", "replace"), m.group("cs") or "",
                                     self.checksum, "noise on the line, or another checksum, or another body group")
        if mismatch:
            raise Garbage(raw, mismatch)


#: the pattern's groups of a checked line, not values
CHECKED_GROUPS = ("body", "cs")
