"""Line protocols of displacement-gauge counters: encode (simulator) and parse (acquisition)."""
from __future__ import annotations

import math

from rodlab.core.enums import Checksum

__all__ = ["xor_checksum", "line_checksum", "checksum_mismatch", "encode_values", "parse_line", "garbage_reason"]


def xor_checksum(payload: bytes) -> str:
    """NMEA-style XOR of all bytes, two upper-case hex digits."""
    c = 0
    for b in payload:
        c ^= b
    return f"{c:02X}"


def line_checksum(payload: bytes, kind: str) -> str:
    """Two upper-case hex digits of ``payload``'s checksum: ``xor`` (NMEA-style) or ``sum8`` (the bytes' sum
    modulo 256)."""
    if kind == Checksum.XOR:
        return xor_checksum(payload)
    if kind == Checksum.SUM8:
        return f"{sum(payload) & 0xFF:02X}"
    raise ValueError(f"unknown checksum {kind!r}; known: xor, sum8")


def checksum_mismatch(body: bytes, cs: str, kind: str, otherwise: str = "noise on the line, or another checksum") -> str:
    """Why a line's checksum ``cs`` (two hex digits) does not fit its ``body`` under ``kind``: naming the other kind
    where that one fits (set it), else ``otherwise``; "" where it fits."""
    if line_checksum(body, kind) == cs.upper():
        return ""
    other = next((k.value for k in (Checksum.XOR, Checksum.SUM8) if k != kind and line_checksum(body, k) == cs.upper()),
                 None)
    return (f"its {kind} checksum does not match, the {other} one does: set checksum = \"{other}\"" if other else
            f"its {kind} checksum does not match ({otherwise})")


def encode_values(values, separator: str = ",", checksum: str = "none") -> bytes:
    """One device line (with CR LF) carrying ``values`` in device units."""
    payload = separator.join(f"{v:+.4f}" for v in values).encode("ascii")
    if checksum != Checksum.NONE:
        payload += b"*" + line_checksum(payload, checksum).encode("ascii")
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
    if checksum != Checksum.NONE:
        if not star or len(cs) != 2:
            return None, "no '*HH' checksum at its end (checksum = \"none\" for a device that sends none)"
        mismatch = checksum_mismatch(body.encode("ascii"), cs, checksum)
        if mismatch:
            return None, mismatch
        text = body
    parts = text.split(separator)
    try:
        vals = [float(p) for p in parts] if len(parts) == n_values else None
    except ValueError:
        vals = None
    if vals is not None and all(math.isfinite(v) for v in vals):
        return vals, ""
    if checksum == Checksum.NONE and star and len(cs) == 2 and all(ch in "0123456789abcdefABCDEF" for ch in cs):
        kind = next((k.value for k in (Checksum.XOR, Checksum.SUM8)
                     if line_checksum(body.encode("ascii"), k) == cs.upper()), Checksum.XOR.value)
        return None, f"it ends with '*HH', a checksum: set checksum = \"{kind}\""
    if len(parts) != n_values:
        other = _other_separator(text, n_values, separator)
        if other is not None:
            return None, f"{n_values} values separated by {other!r}: set separator = {other!r}"
        return None, f"{len(parts)} value(s) separated by {separator!r}, the profile expects n_values = {n_values}"
    return None, "a value that is not a finite number (units or a status word in the line?)"


def _other_separator(text: str, n_values: int, separator: str) -> str | None:
    """The common separator that splits ``text`` into ``n_values`` numbers where ``separator`` does not (review:
    a ';' line had been blamed on n_values)."""
    for sep in (",", ";", "\t", " "):
        if sep == separator:
            continue
        parts = text.split(sep)
        try:
            if len(parts) == n_values and all(math.isfinite(float(p)) for p in parts):
                return sep
        except ValueError:
            continue
    return None
