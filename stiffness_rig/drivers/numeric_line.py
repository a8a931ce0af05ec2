"""``numeric_line``: a counter that prints all its values as one line of bare numbers (rodlab's original
protocol): ``query`` (a request, one line back) or ``stream`` (the device pushes lines), a separator and an
optional checksum ``*HH`` (NMEA-style XOR, or the bytes' sum modulo 256). Values are named by their place in the
line: ``0``, ``1``, ..."""
from __future__ import annotations

from rodlab.core.enums import Checksum, LineProtocol

from ..protocol import garbage_reason, parse_line
from .base import INIT_SETTING, Driver, Garbage, Link, Setting, unescape

__all__ = ["NumericLine"]


class NumericLine(Driver):
    name = "numeric_line"
    summary = "one line of bare numbers per reading (query or stream), optional checksum *HH (xor or sum8)"
    settings = (Setting("mode", str, LineProtocol.QUERY.value,
                        "query: request -> one line; stream: the device pushes lines",
                        tuple(m.value for m in LineProtocol)),
                Setting("request", str, "R\\r\\n", "query: what asks for a reading"),
                Setting("separator", str, ",", "between the values of a line"),
                Setting("checksum", str, Checksum.NONE.value, "none, xor or sum8: the line ends with *HH, the "
                        "XOR or the sum modulo 256 of the bytes before *", tuple(m.value for m in Checksum)),
                Setting("n_values", int, 0, "values per line (0: one more than the highest channel value)"),
                INIT_SETTING)
    simulator = "SimNumericLine"

    @property
    def values(self) -> tuple:
        return tuple(str(i) for i in range(max(int(self.config.get("n_values", 0)), 1)))

    def poll(self, link: Link) -> dict:
        c = self.config
        if c.get("mode", "query") == "query":
            link.clear_input()
            link.write(unescape(c.get("request", "R\\r\\n")).encode("ascii"))
            raw = link.readline()
        else:
            raw = link.latest_line()
        vals = parse_line(raw, int(c["n_values"]), c.get("separator", ","), c.get("checksum", "none"))
        if vals is None:
            raise Garbage(raw, garbage_reason(raw, int(c["n_values"]), c.get("separator", ","),
                                              c.get("checksum", "none")))
        return {str(i): v for i, v in enumerate(vals)}
