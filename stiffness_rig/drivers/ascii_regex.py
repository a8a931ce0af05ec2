"""``ascii_regex``: a sensor controller's ASCII protocol (Keyence, Ono Sokki, most amplifiers): a request line
and an answer matched by a regular expression whose named groups are the values, e.g. ``request = "M0\\r"``,
``pattern = "^M0,(?P<out1>[-+0-9.]+),(?P<out2>[-+0-9.]+)$"``. Scale and units of each value are the channel's
(the profile). An empty request: the controller pushes its lines."""
from __future__ import annotations

import math
import re

from .base import Driver, Garbage, Link, Setting, unescape

__all__ = ["AsciiRegex"]


class AsciiRegex(Driver):
    name = "ascii_regex"
    summary = "a request line and an answer matched by a regular expression; its named groups are the values"
    settings = (Setting("request", str, "", "what asks for a reading (empty: the controller pushes lines)"),
                Setting("pattern", str, None, "regular expression of one answer line (stripped), a named group "
                                              "(?P<name>...) per value"),
                Setting("eol", str, "\\n", "the character that ends an answer line"))
    simulator = "SimAsciiRegex"

    def __init__(self, config: dict) -> None:
        super().__init__(config)
        self.regex = re.compile(config["pattern"])

    @property
    def values(self) -> tuple:
        return tuple(self.regex.groupindex)

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
