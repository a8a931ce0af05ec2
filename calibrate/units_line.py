"""What a ``# units: ...`` line of a points or sockets file says: the formats' lengths are millimetres whatever the
line says (the columns' ``_mm``), so a line that leads with another length unit is a file in that unit."""
from __future__ import annotations

import re

__all__ = ["units_line_problem"]

#: length units a ``# units:`` line may name that are not the formats' millimetres, and their factor to mm
_OTHER_LENGTHS = {"m": 1000.0, "metre": 1000.0, "metres": 1000.0, "meter": 1000.0, "meters": 1000.0, "cm": 10.0,
                  "um": 1e-3, "µm": 1e-3, "micron": 1e-3, "microns": 1e-3, "in": 25.4, "inch": 25.4, "inches": 25.4}


def units_line_problem(value: str) -> str | None:
    """What a ``# units: ...`` line of a points or sockets file says wrongly: a length unit other than millimetres
    (the lengths are millimetres whatever the line says: ``x_mm``); None for mm (and deg)."""
    tokens = re.findall(r"[a-zµ]+", value.lower().replace("\u03bc", "\u00b5"))   # Greek mu as the micro sign
    other = tokens[:1] if tokens and tokens[0] in _OTHER_LENGTHS else []     # the unit the line leads with ("mm in
    if not other:                                                           # the tracker frame" is millimetres)
        return None
    return (f"'# units: {value.strip()}' names {other[0]}: rodlab reads the lengths as millimetres whatever the line "
            f"says (the columns' _mm); convert the numbers ({other[0]} x {_OTHER_LENGTHS[other[0]]:g} = mm) and write "
            "mm on the line, or delete it")
