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


def parse_line(raw: bytes, n_values: int, separator: str = ",", checksum: str = "none"):
    """Values of one device line, or ``None`` for garbage (bad checksum, wrong count, not numbers)."""
    try:
        text = raw.decode("ascii").strip()
    except UnicodeDecodeError:
        return None
    if not text:
        return None
    if checksum == "xor":
        body, star, cs = text.rpartition("*")
        if not star or len(cs) != 2 or xor_checksum(body.encode("ascii")) != cs.upper():
            return None
        text = body
    parts = text.split(separator)
    if len(parts) != n_values:
        return None
    try:
        vals = [float(p) for p in parts]
    except ValueError:
        return None
    if not all(math.isfinite(v) for v in vals):
        return None
    return vals
