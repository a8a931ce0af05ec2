"""Ball-in-socket and ball-bar readings (``*.sockets.csv``): joint angles only, no external instrument.

The robot carries a ball. An artefact on the table has sockets (kinematic seats) whose distances from one
another are known (the MUKCa tool: two sockets 50 mm apart; a plate with several). The artefact is placed in
turn at several places in the workspace (placements); at each, the ball is put in a socket and the joint
angles recorded, many times with different arm configurations. Where a socket is in the robot's frame is
unknown: it is fitted, one centre per placement and socket, with the robot's parameters (jointly across all
placements, :mod:`calibrate.socket_fit`). A ball bar is the same with a length: the bar joins a pivot (its
fixed ball, the "socket") to the robot's ball and reads their distance (``length_mm``).

File: comment lines ``# key: value`` before the header (others ignored), then
``placement,socket,q1..qn[,length_mm]`` (q in deg; placement and socket positive integers; ``length_mm``
present makes every row a ball-bar reading).
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from pathlib import Path
import difflib

import numpy as np

from rodlab.core.fileio import atomic_write_text

from .campaign import leading_comments, read_table, read_text_file
from .units_line import units_line_problem
from .errors import CalibrationError

__all__ = ["SocketDistance", "SocketReadings", "read_sockets", "write_sockets", "SEAT_SIGMA_MM", "DISTANCE_SIGMA_MM",
           "LENGTH_SIGMA_MM"]

#: default standard uncertainty of the ball's seat in a socket, per coordinate [mm] (a machined kinematic seat
#: with a ground ball; a 3D-printed socket has more play: state it with ``# seat_sigma_mm``)
SEAT_SIGMA_MM = 0.02
#: default standard uncertainty of a known socket distance [mm] (the artefact measured on a CMM)
DISTANCE_SIGMA_MM = 0.01
#: default standard uncertainty of a ball-bar length reading [mm] (a telescopic ball bar's transducer)
LENGTH_SIGMA_MM = 0.002


@dataclass(frozen=True)
class SocketDistance:
    """A known distance between two sockets of the artefact, the same at every placement.

    a, b : socket numbers (a != b); mm : the centre-to-centre distance [mm], > 0
    """

    a: int
    b: int
    mm: float

    def __post_init__(self) -> None:
        if self.a == self.b or not self.mm > 0:
            raise ValueError(f"a socket distance joins two sockets (got {self.a}-{self.b}) and is > 0 (got {self.mm})")


@dataclass(frozen=True)
class SocketReadings:
    """The readings of one ``*.sockets.csv``.

    q_rad : shape=(N, n) joint angles [rad]; placement, socket : shape=(N,) int, where the artefact was and
    which socket (ball bar: which pivot) the ball sat in; length_mm : shape=(N,) ball-bar length [mm] (ball
    centre to pivot centre) or None for seat readings; distances : known socket distances;
    tool_mm : shape=(3,) the ball centre in {n} [mm], or None for the robot description's tip point;
    seat_sigma_mm, distance_sigma_mm, length_sigma_mm : standard uncertainties [mm] (1 sigma);
    path; lines : shape=(N,) the file line of each reading
    """

    q_rad: np.ndarray
    placement: np.ndarray
    socket: np.ndarray
    length_mm: np.ndarray | None = None
    distances: tuple = ()
    tool_mm: np.ndarray | None = None
    seat_sigma_mm: float = SEAT_SIGMA_MM
    distance_sigma_mm: float = DISTANCE_SIGMA_MM
    length_sigma_mm: float = LENGTH_SIGMA_MM
    path: Path | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    def __post_init__(self) -> None:
        N = np.shape(self.q_rad)[0]
        for k in ("placement", "socket") + (("length_mm",) if self.length_mm is not None else ()):
            if np.shape(getattr(self, k)) != (N,):
                raise ValueError(f"{k} must have shape ({N},), got {np.shape(getattr(self, k))}")
        if self.tool_mm is not None and np.shape(self.tool_mm) != (3,):
            raise ValueError(f"tool_mm must have shape (3,), got {np.shape(self.tool_mm)}")
        for k in ("seat_sigma_mm", "distance_sigma_mm", "length_sigma_mm"):
            if not getattr(self, k) > 0:
                raise ValueError(f"{k} must be > 0, got {getattr(self, k)}")

    @property
    def n(self) -> int:
        return int(self.placement.size)

    @property
    def ball_bar(self) -> bool:
        return self.length_mm is not None

    def groups(self) -> list[tuple[int, int]]:
        """The (placement, socket) pairs in order of appearance: one unknown centre each."""
        seen: dict = {}
        for key in zip(self.placement.tolist(), self.socket.tolist()):
            seen.setdefault(key, None)
        return list(seen)

    def group_index(self) -> np.ndarray:
        """Index into :meth:`groups` of every reading, shape=(N,)."""
        index = {g: k for k, g in enumerate(self.groups())}
        return np.array([index[g] for g in zip(self.placement.tolist(), self.socket.tolist())], int)

    def distance_pairs(self) -> tuple[np.ndarray, np.ndarray]:
        """The known distances as they apply: (K, 2) indices into :meth:`groups` of the two sockets, one row per
        placement and pair whose two sockets both have readings there, and (K,) the stated distances [mm]."""
        index = {g: k for k, g in enumerate(self.groups())}
        rows = [((index[(pl, d.a)], index[(pl, d.b)]), d.mm) for pl in dict.fromkeys(self.placement.tolist())
                for d in self.distances if (pl, d.a) in index and (pl, d.b) in index]
        return np.array([r[0] for r in rows], int).reshape(-1, 2), np.array([r[1] for r in rows], float)

    def subset(self, placements) -> "SocketReadings":
        """The readings of some placements only (a fit on some, a check on the others)."""
        m = np.isin(self.placement, list(placements))
        return replace(self, q_rad=self.q_rad[m], placement=self.placement[m], socket=self.socket[m],
                       length_mm=None if self.length_mm is None else self.length_mm[m],
                       lines=self.lines[m] if self.lines.size else self.lines)


_KEYS = ("distance_mm", "tool_mm", "seat_sigma_mm", "distance_sigma_mm", "length_sigma_mm")


#: a comment key that names a quantity (a unit suffix, or ``units``): meant as data, refused when unknown; other
#: comment keys (``Source``, ``robot``, ``date``) are the user's notes
_DATA_KEY = re.compile(r"[a-z0-9_]+_(mm|m|um|deg|rad|kg|g|n|s)", re.IGNORECASE)


def _meta(p: Path, text: str) -> dict:
    """``# key: value`` lines before the header: {key: (line, value)}; a near miss of a known key, an unknown key
    naming a quantity (:data:`_DATA_KEY`: ``tool_offset_mm``) and a units line naming a length other than mm are
    refused, other comments (``# Source: ...``) are ignored."""
    meta = {}
    for k, key, value in leading_comments(text):
        if not re.fullmatch(r"[A-Za-z_]+", key):
            continue
        if key.lower() in ("unit", "units"):                # a units line: read for what it says, not kept
            if (problem := units_line_problem(value)):
                raise CalibrationError(problem, path=p, line=k, key=key)
            continue
        if key not in _KEYS:
            near = difflib.get_close_matches(key, _KEYS, n=1, cutoff=0.8)
            if near:                                      # a misspelt key, not a comment of the user's
                raise CalibrationError(f"unknown key {key!r}; did you mean {near[0]!r}? A sockets file knows "
                                       f"{list(_KEYS)}", path=p, line=k, key=key)
            if _DATA_KEY.fullmatch(key):                  # a number with a unit the user meant to be read
                raise CalibrationError(f"unknown key {key!r}: a sockets file knows {list(_KEYS)}; rodlab would not "
                                       "read it. Remove the line or give the value under one of those keys", path=p,
                                       line=k, key=key)
            continue
        if key in meta:
            raise CalibrationError(f"{key!r} is given twice (also on line {meta[key][0]})", path=p, line=k, key=key)
        meta[key] = (k, value)
    return meta


def _positive(p: Path, meta: dict, key: str, default: float) -> float:
    if key not in meta:
        return default
    line, val = meta[key]
    v = _number(val)
    if not (np.isfinite(v) and v > 0):
        raise CalibrationError(f"expected a standard deviation > 0 [mm], got {val!r}", path=p, line=line, key=key)
    return v


def _tool(p: Path, meta: dict) -> np.ndarray | None:
    if "tool_mm" not in meta:
        return None
    line, val = meta["tool_mm"]
    try:
        arr = np.array([float(v) for v in val.split(",")])
    except ValueError:
        arr = np.zeros(0)
    if arr.size != 3 or not np.all(np.isfinite(arr)):
        raise CalibrationError(f"expected 3 finite numbers separated by commas (the ball centre in {{n}} [mm]), "
                               f"got {val!r}", path=p, line=line, key="tool_mm")
    return arr


def _number(text: str) -> float:
    try:
        return float(text)
    except ValueError:
        return float("nan")


def _distances(p: Path, meta: dict) -> tuple:
    """``# distance_mm: 1-2 = 50.0; 2-3 = 50.0``: known centre-to-centre distances of socket pairs."""
    if "distance_mm" not in meta:
        return ()
    line, val = meta["distance_mm"]
    out, seen = [], set()
    for item in filter(None, (s.strip() for s in val.split(";"))):
        m = re.match(r"^(\d+)\s*-\s*(\d+)\s*=\s*(\S+)$", item)
        if not m or int(m.group(1)) == int(m.group(2)) or not 0 < _number(m.group(3)) < np.inf:
            raise CalibrationError(f"expected 'A-B = DISTANCE' (two different socket numbers and a distance > 0 "
                                   f"[mm]; pairs separated by ';'), got {item!r}", path=p, line=line, key="distance_mm")
        pair = frozenset((int(m.group(1)), int(m.group(2))))
        if pair in seen:
            raise CalibrationError(f"the pair {item.split('=')[0].strip()} is given twice", path=p, line=line,
                                   key="distance_mm")
        seen.add(pair)
        out.append(SocketDistance(int(m.group(1)), int(m.group(2)), float(m.group(3))))
    return tuple(out)


def read_sockets(path, n_joints: int = 6) -> SocketReadings:
    """Read a ``*.sockets.csv``; every problem names the file, line and key (see the module docstring)."""
    p, text = read_text_file(path)
    meta = _meta(p, text)
    qs = [f"q{i}" for i in range(1, n_joints + 1)]
    header, rows = read_table(p, text, ["placement", "socket"] + qs, ["length_mm"])
    for k, r in rows:
        for col in ("placement", "socket"):
            if r[col] != int(r[col]) or r[col] < 1:
                raise CalibrationError(f"expected a positive integer, got {r[col]:g}", path=p, line=k, key=col)
        if "length_mm" in header and not r["length_mm"] > 0:
            raise CalibrationError(f"expected a ball-bar length > 0 [mm], got {r['length_mm']:g}", path=p, line=k,
                                   key="length_mm")
    out = SocketReadings(
        np.deg2rad([[r[c] for c in qs] for _, r in rows]), np.array([int(r["placement"]) for _, r in rows]),
        np.array([int(r["socket"]) for _, r in rows]),
        np.array([r["length_mm"] for _, r in rows]) if "length_mm" in header else None, _distances(p, meta),
        _tool(p, meta), _positive(p, meta, "seat_sigma_mm", SEAT_SIGMA_MM),
        _positive(p, meta, "distance_sigma_mm", DISTANCE_SIGMA_MM),
        _positive(p, meta, "length_sigma_mm", LENGTH_SIGMA_MM), p, np.array([k for k, _ in rows]))
    _check_layout(out)
    return out


def _check_layout(r: SocketReadings) -> None:
    """Enough readings per socket to locate it, and distances that name sockets the file has."""
    sockets = set(r.socket.tolist())
    for d in r.distances:
        missing = sorted({d.a, d.b} - sockets)
        if missing:
            raise CalibrationError(f"distance {d.a}-{d.b} names socket(s) {missing} that no reading uses (the file "
                                   f"has sockets {sorted(sockets)})", path=r.path, key="distance_mm")
    least = 4 if r.ball_bar else 2
    for g, count in zip(*np.unique(r.group_index(), return_counts=True)):
        if count < least:
            pl, so = r.groups()[g]
            line = int(r.lines[r.group_index() == g][0]) if r.lines.size else None
            raise CalibrationError(f"placement {pl}, socket {so} has {count} reading(s): at least {least} are needed "
                                   f"to locate it (record more arm configurations there, or drop the row)",
                                   path=r.path, line=line, key="socket")


def write_sockets(path, readings: SocketReadings, comment: str = "") -> Path:
    """Write ``readings`` as a ``*.sockets.csv`` (atomically; q in deg with 6 decimals)."""
    r = readings
    head = [f"# {line}" for line in comment.splitlines()]
    if r.distances:
        head.append("# distance_mm: " + "; ".join(f"{d.a}-{d.b} = {d.mm:g}" for d in r.distances))
    if r.tool_mm is not None:
        head.append("# tool_mm: " + ", ".join(f"{v:g}" for v in r.tool_mm))
    head += [f"# seat_sigma_mm: {r.seat_sigma_mm:g}", f"# distance_sigma_mm: {r.distance_sigma_mm:g}",
             f"# length_sigma_mm: {r.length_sigma_mm:g}"]
    cols = ["placement", "socket"] + [f"q{i + 1}" for i in range(r.q_rad.shape[1])] + (
        ["length_mm"] if r.ball_bar else [])
    rows = []
    for k in range(r.n):
        cells = [str(r.placement[k]), str(r.socket[k])] + [f"{v:.6f}" for v in np.rad2deg(r.q_rad[k])]
        if r.ball_bar:
            cells.append(f"{r.length_mm[k]:.6f}")
        rows.append(",".join(cells))
    return atomic_write_text(path, "\n".join(head + [",".join(cols)] + rows) + "\n")
