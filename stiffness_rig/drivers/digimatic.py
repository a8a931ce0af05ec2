"""``digimatic``: a Mitutoyo Digimatic indicator behind an RS-232 / USB interface (e.g. a DMX / IT-016U style
Digimatic-to-serial unit): a request (default ``"1\\r"``) answered with ``01A+00012.345`` + CR: two digits
of channel number, the data code (``A``: a reading), sign and value in the display unit (mm on a metric
indicator). ``91`` followed by a digit is the interface's error answer (no indicator, no data): garbage. One
value, ``value``."""
from __future__ import annotations

import re

from .base import Driver, Garbage, Link, Setting, unescape

__all__ = ["Digimatic", "DIGIMATIC_LINE", "format_digimatic"]

#: channel, data code, sign, value
DIGIMATIC_LINE = re.compile(r"^(\d{2})([A-Z])([+-])(\d{1,7}(?:\.\d*)?)$")


def format_digimatic(value: float, channel: int = 1, decimals: int = 3) -> bytes:
    """One answer line, e.g. ``01A+00012.345\\r`` (width 9 for the digits and point: the interface's)."""
    sign = "-" if value < 0 else "+"
    return f"{channel:02d}A{sign}{abs(value):0{9}.{decimals}f}\r".encode("ascii")


class Digimatic(Driver):
    name = "digimatic"
    summary = "Mitutoyo Digimatic via an RS-232 / USB interface: request -> '01A+00012.345'"
    settings = (Setting("request", str, "1\\r", "what asks the interface for a reading"),
                Setting("interface_channel", int, 0, "the interface channel the answer must carry (0: any)"))
    simulator = "SimDigimatic"

    @property
    def values(self) -> tuple:
        return ("value",)

    def poll(self, link: Link) -> dict:
        link.clear_input()
        link.write(unescape(self.config.get("request", "1\\r")).encode("ascii"))
        raw = link.readline(b"\r")
        text = raw.decode("ascii", "replace").strip()
        m = DIGIMATIC_LINE.match(text)
        if not m or m.group(2) != "A":
            raise Garbage(raw, "not a Digimatic reading")
        want = int(self.config.get("interface_channel", 0))
        if want and int(m.group(1)) != want:
            raise Garbage(raw, f"channel {m.group(1)}, expected {want:02d}")
        v = float(m.group(4))
        return {"value": -v if m.group(3) == "-" else v}
