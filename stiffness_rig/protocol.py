"""Line protocols of displacement-gauge counters: encode (simulator) and parse (acquisition)."""
from __future__ import annotations

import math

__all__ = ["xor_checksum", "encode_values", "parse_line"]


def xor_checksum(payload: bytes) -> str:
    """NMEA-style XOR of all bytes, two upper-case hex digits."""
    c = 0
    for b in payload:
        c ^= b
    return f"{c:02X}"


def encode_values(values, separator: str = ",", checksum: str = "none") -> bytes:
    """One device line (with CR LF) carrying ``values`` in device units."""
    payload = separator.join(f"{v:+.4f}" for v in values).encode("ascii")
    if checksum == "xor":
        payload += b"*" + xor_checksum(payload).encode("ascii")
    return payload + b"\r\n"


def garbage_reason(raw: bytes, n_values: int, separator: str = ",", checksum: str = "none") -> str:
    """Why :func:`parse_line` refuses ``raw``, with the profile key to look at (a technician trial: three wrong
    settings had each given only "answers nothing usable"); "" for a line it reads."""
    return _parse(raw, n_values, separator, checksum)[1]


def parse_line(raw: bytes, n_values: int, separator: str = ",", checksum: str = "none"):
    """Values of one device line, or ``None`` for garbage (bad checksum, wrong count, not numbers)."""
    return _parse(raw, n_values, separator, checksum)[0]


def _parse(raw: bytes, n_values: int, separator: str, checksum: str) -> tuple[list | None, str]:
    """(the line's values, "") or (None, why it is garbage)."""
    try:
        text = raw.decode("ascii").strip()
    except UnicodeDecodeError:
        return None, "not ASCII text (the baud rate or the parity?)"
    if not text:
        return None, "an empty line"
    body, star, cs = text.rpartition("*")
    if checksum == "xor":
        if not star or len(cs) != 2:
            return None, "no '*HH' checksum at its end (checksum = \"none\" for a device that sends none)"
        if xor_checksum(body.encode("ascii")) != cs.upper():
            return None, "its XOR checksum does not match (noise on the line, or another checksum)"
        text = body
    parts = text.split(separator)
    try:
        vals = [float(p) for p in parts] if len(parts) == n_values else None
    except ValueError:
        vals = None
    if vals is not None and all(math.isfinite(v) for v in vals):
        return vals, ""
    if checksum != "xor" and star and len(cs) == 2 and all(ch in "0123456789abcdefABCDEF" for ch in cs):
        return None, "it ends with '*HH', a checksum: set checksum = \"xor\""
    if len(parts) != n_values:
        return None, f"{len(parts)} value(s) separated by {separator!r}, the profile expects n_values = {n_values}"
    return None, "a value that is not a finite number (units or a status word in the line?)"
