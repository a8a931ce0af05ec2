"""Stiffness-rig recordings (contract ``rodlab.rig/1``): read with line/column errors, append safely.

File layout: comment lines ``# key: value`` (at least ``rod`` and ``format``), then a CSV header and one
row per sample::

    time_s,step,repeat,phase,load_axis,mass_kg,disp_x_mm,disp_y_mm,disp_z_mm[,temp_C][,force_N]

``disp_*`` may be empty where that axis is not measured; ``force_N`` (contract v1.1) is a load cell's reading
[N] along ``load_axis``, empty where not measured. Every sample of a hold (``step``) has the same
``mass_kg``, ``load_axis``, ``phase`` and ``repeat``. Each load axis's series starts with a mass-0 hold.
"""
from __future__ import annotations

import csv
import io
import logging
import math
import os
from dataclasses import dataclass, field, fields, replace
from pathlib import Path

import numpy as np

from rodlab.core.compliance import PLAUSIBLE_C_F_MM_PER_N
from rodlab.core.enums import LoadAxis, Phase
from rodlab.core.fileio import read_text_checked, separator_problem
from rodlab.core.units import G0

from .errors import RigError
from .recording_header import COLUMNS, FORMAT_RIG, OPTIONAL_COLUMNS, check_header, read_header, split_header, unread_unit_lines

log = logging.getLogger(__name__)

#: on-axis slopes all below this [mm/N] are no measuring rod's (a straight rod is ~1e-5 along its own axis alone):
#: metres, or grams as kg
STIFF_LIMIT_MM_PER_N = 1e-5
#: a hung mass beyond this [kg] is no stiffness rig's (the paper's: 0.5-2 kg): grams
PLAUSIBLE_RIG_MASS_KG = 50.0
_AXES = "xyz"

__all__ = ["RigRecording", "read_recording", "read_header", "RecordingWriter", "FORMAT_RIG", "COLUMNS", "OPTIONAL_COLUMNS",
           "format_row"]



@dataclass
class RigRecording:
    """A stiffness-rig recording (all samples).

    Attributes
    ----------
    meta : the ``# key: value`` header (``rod``, ``format``, ...)
    time_s : shape=(n,) [s]; step, repeat : shape=(n,) int; phase : shape=(n,) of :class:`Phase`
    load_axis : shape=(n,) of :class:`LoadAxis`; mass_kg : shape=(n,) [kg] (hanger included)
    disp_mm : shape=(n, 3) [mm] ball-centre displacement in {T}, NaN where not measured
    temp_C : shape=(n,) [degC] or None
    force_N : shape=(n,) [N] the load cell's reading along ``load_axis`` (NaN where not measured), or None
        without a ``force_N`` column
    """

    meta: dict
    time_s: np.ndarray
    step: np.ndarray
    repeat: np.ndarray
    phase: np.ndarray
    load_axis: np.ndarray
    mass_kg: np.ndarray
    disp_mm: np.ndarray
    temp_C: np.ndarray | None = None
    path: Path | None = field(default=None, compare=False)
    force_N: np.ndarray | None = None

    def __post_init__(self) -> None:
        n = self.time_s.shape[0]
        for name in ("step", "repeat", "phase", "load_axis", "mass_kg"):
            if getattr(self, name).shape != (n,):
                raise ValueError(f"{name} must have shape ({n},), got {getattr(self, name).shape}")
        if self.disp_mm.shape != (n, 3):
            raise ValueError(f"disp_mm must have shape ({n}, 3), got {self.disp_mm.shape}")
        if self.force_N is not None and np.shape(self.force_N) != (n,):
            raise ValueError(f"force_N must have shape ({n},), got {np.shape(self.force_N)}")

    @property
    def has_force(self) -> bool:
        """The recording has a load cell's readings (a ``force_N`` column with at least one value)."""
        return self.force_N is not None and bool(np.isfinite(self.force_N).any())

    @property
    def n(self) -> int:
        return int(self.time_s.shape[0])

    def subset(self, keep: np.ndarray) -> "RigRecording":
        """The rows where ``keep`` (bool, shape=(n,)) is true; the header and path as they are."""
        return replace(self, **{f.name: getattr(self, f.name)[keep] for f in fields(self)
                                if isinstance(getattr(self, f.name), np.ndarray)})

    def without_readings(self, rows: np.ndarray, comps: np.ndarray) -> "RigRecording":
        """The recording with the gauge readings at (``rows``, ``comps``) blanked (NaN): readings left out as a
        glitch or as no rod's; the rest as it is."""
        disp = self.disp_mm.copy()
        disp[rows, comps] = np.nan
        return replace(self, disp_mm=disp)

    def series(self) -> np.ndarray:
        """shape=(n,) int: the series of each row, a run of one load axis (and sign) in recording order; the gauges
        are zeroed whenever it changes, also when an axis is loaded a second time (y, z, y)."""
        la = list(self.load_axis)
        return np.cumsum([0] + [a != b for a, b in zip(la[1:], la[:-1])]).astype(int)

    @property
    def rod(self) -> str:
        return str(self.meta.get("rod", ""))

    def measured_axes(self) -> list[int]:
        """Components (0..2) that have at least one reading."""
        return [i for i in range(3) if np.isfinite(self.disp_mm[:, i]).any()]

    def loaded_axes(self) -> list[int]:
        """The axes (0..2 for x..z, either sign) some load of the recording pulls along: the columns of C_F it
        measures."""
        return sorted({LoadAxis(a).index for a in self.load_axis})

    def unit_slips(self) -> list[str]:
        """Slopes no measuring rod has, each with the unit slip that gives them: a load axis whose own gauge moves
        by more than :data:`~rodlab.core.compliance.PLAUSIBLE_C_F_MM_PER_N` per newton of its masses (um written
        as mm), or every measured axis less than :data:`STIFF_LIMIT_MM_PER_N` (metres written as mm, or grams as
        kg, scale every axis alike; a straight rod is that stiff along its own axis alone), or a mass beyond
        :data:`PLAUSIBLE_RIG_MASS_KG` (grams)."""
        slopes = self._on_axis_slopes()
        out = [f"the {_AXES[a]} gauge moves {k:.4g} mm per N of the {_AXES[a]} load; no measuring rod is that soft "
               f"(beyond {PLAUSIBLE_C_F_MM_PER_N:g} mm/N; the paper's carbon 1# 0.0005-0.006 mm/N, its steel 6# up to "
               "0.12 mm/N): if disp_mm is in um, divide it by 1000"
               for a, k in slopes.items() if k > PLAUSIBLE_C_F_MM_PER_N]
        if slopes and all(k < STIFF_LIMIT_MM_PER_N for k in slopes.values()):
            out.append(f"every gauge moves less than {STIFF_LIMIT_MM_PER_N:g} mm per N of its own load ("
                       + ", ".join(f"{_AXES[a]} {k:.3g}" for a, k in slopes.items()) + "); no measuring rod is that "
                       "stiff on every axis: a displacement in metres (multiply by 1000) or masses in grams (divide "
                       "mass_kg by 1000)?")
        heaviest = float(np.nanmax(self.mass_kg)) if self.n else 0.0
        if heaviest > PLAUSIBLE_RIG_MASS_KG:       # grams with readings in um: the slopes right, the rest not
            out.append(f"mass_kg reaches {heaviest:g}; no rig hangs more than {PLAUSIBLE_RIG_MASS_KG:g} kg on a measuring "
                       "rod (the paper's: 0.5-2 kg): if these are grams, divide mass_kg by 1000 (readings in um "
                       "with masses in g give the right slopes, but not the noise, friction or zero crossings)")
        return out

    def _on_axis_slopes(self) -> dict:
        """{component: |slope| [mm/N]} of each measured gauge against its own load axis's signed load."""
        axis = np.array([str(getattr(v, "value", v)) for v in self.load_axis])
        sign = np.where(np.char.startswith(axis, "-"), -1.0, 1.0)
        out = {}
        for a in self.measured_axes():
            on = (np.char.lstrip(axis, "-") == _AXES[a]) & np.isfinite(self.disp_mm[:, a])
            load = sign[on] * self.mass_kg[on] * G0
            if on.sum() >= 3 and np.ptp(load) > 0:
                out[a] = abs(float(np.polyfit(load, self.disp_mm[on, a], 1)[0]))
        return out

    def steps(self) -> np.ndarray:
        """Distinct step numbers in recording order."""
        _, first = np.unique(self.step, return_index=True)
        return self.step[np.sort(first)]


def _float(cell: str, path, line: int, col: str, allow_empty: bool = False) -> float:
    if cell.strip() == "":
        if allow_empty:
            return math.nan
        raise RigError("empty cell; expected a number", path=path, line=line, key=col)
    try:
        v = float(cell)
    except ValueError:
        raise RigError(f"expected a number, got {cell!r}", path=path, line=line, key=col) from None
    if not math.isfinite(v):
        hint = ("; a reading the gauge did not give is an empty cell (pandas: to_csv(na_rep=''))"
                if allow_empty and math.isnan(v) else "")
        raise RigError(f"expected a finite number, got {cell!r}{hint}", path=path, line=line, key=col)
    return v


def _int(cell: str, path, line: int, col: str) -> int:
    v = _float(cell, path, line, col)
    if v != int(v) or v < 0 or v > 2**31 - 1:
        raise RigError(f"expected a non-negative integer below 2^31, got {cell!r}", path=path, line=line, key=col)
    return int(v)


def _row(row: list[str], ix: dict, p: Path, k: int, has_temp: bool) -> tuple:
    """One sample line ``k``: (line, time, step, repeat, phase, load axis, mass, [dx, dy, dz], temp, force)."""
    t = _float(row[ix["time_s"]], p, k, "time_s")
    step = _int(row[ix["step"]], p, k, "step")
    rep = _int(row[ix["repeat"]], p, k, "repeat")
    try:
        ph = Phase(row[ix["phase"]].strip())
    except ValueError:
        raise RigError(f"expected 'load' or 'unload', got {row[ix['phase']]!r}", path=p, line=k,
                       key="phase") from None
    try:
        ax = LoadAxis(row[ix["load_axis"]].strip())
    except ValueError:
        raise RigError(f"unknown load axis {row[ix['load_axis']]!r}; expected one of "
                       f"{[a.value for a in LoadAxis]}", path=p, line=k, key="load_axis") from None
    m = _float(row[ix["mass_kg"]], p, k, "mass_kg")
    if m < 0:
        raise RigError(f"mass must be >= 0, got {m}", path=p, line=k, key="mass_kg")
    disp = [_float(row[ix[c]], p, k, c, allow_empty=True) for c in ("disp_x_mm", "disp_y_mm", "disp_z_mm")]
    temp = _float(row[ix["temp_C"]], p, k, "temp_C", allow_empty=True) if has_temp else math.nan
    force = _float(row[ix["force_N"]], p, k, "force_N", allow_empty=True) if "force_N" in ix else math.nan
    return (k, t, step, rep, ph, ax, m, disp, temp, force)


def read_recording(path: str | Path, text: str | None = None) -> RigRecording:
    """Read a ``*.rig.csv``; every malformed cell or rule names its line and column."""
    p = Path(path)
    if text is None:
        text = read_text_checked(p, RigError)
    lines = text.splitlines()
    meta, i = split_header(lines)
    if meta.get("format") != FORMAT_RIG:
        got = f"got {meta['format']!r}" if meta.get("format") else "the file has none (rig acquire and rig simulate write it)"
        raise RigError(f"expected a comment line '# format: {FORMAT_RIG}' before the header; {got}", path=p, line=1,
                       key="format")
    if "rod" not in meta:
        raise RigError("expected a comment line '# rod: NAME' before the header", path=p, line=1, key="rod")
    if i >= len(lines):
        raise RigError("no header line", path=p, line=i + 1)
    header_line = i + 1
    if (problem := separator_problem(lines[i])) is not None:
        raise RigError(problem, path=p, line=header_line)
    header = [h.strip() for h in next(csv.reader([lines[i]]))]
    check_header(header, p, header_line)
    ix = {c: header.index(c) for c in header}
    has_temp = "temp_C" in ix
    rows = _data_rows(lines, i + 1, header, ix, p, has_temp)
    if not rows:
        raise RigError("no samples after the header", path=p, line=header_line)
    _check_holds(rows, p)
    arr = lambda j, dt=float: np.array([r[j] for r in rows], dtype=dt)  # noqa: E731
    rec = RigRecording(meta, arr(1), arr(2, int), arr(3, int), np.array([r[4] for r in rows], dtype=object),
                       np.array([r[5] for r in rows], dtype=object), arr(6), np.array([r[7] for r in rows]),
                       arr(8) if has_temp else None, p, arr(9) if "force_N" in ix else None)
    if not rec.measured_axes():
        raise RigError("no displacement column has any reading", path=p, line=header_line, key="disp_x_mm")
    for problem in rec.unit_slips() + unread_unit_lines(meta):
        log.warning("%s: %s", p, problem)
    return rec


def _data_rows(lines: list[str], start: int, header: list[str], ix: dict, p: Path, has_temp: bool) -> list[tuple]:
    """The sample rows from line index ``start`` on (comment and blank lines skipped). A last line with fewer cells
    than the header is a sample cut off by an interrupted acquisition: it is left out with a warning (``rig
    acquire`` drops it and resumes after the last complete hold); a last line with every cell is kept, with or
    without its newline (other tools end files without one). A line that repeats the header (or starts with
    ``time_s``) is two recordings joined."""
    rows = []
    numbered = [(k, row) for k, row in enumerate(csv.reader(lines[start:]), start=start + 1)
                if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    for j, (k, row) in enumerate(numbered):
        if row[0].strip() == "time_s":
            raise RigError(f"this line repeats the header: two recordings joined into one file? Split the file "
                           f"before line {k}, or delete the repeated header if it is one recording", path=p, line=k)
        if j == len(numbered) - 1 and len(row) < len(header):
            log.warning("%s, line %d: the last line has %d of %d cells, a sample cut off (an interrupted "
                        "recording?); left out", p, k, len(row), len(header))
            break
        if len(row) != len(header):
            raise RigError(f"expected {len(header)} cells, got {len(row)}", path=p, line=k)
        rows.append(_row(row, ix, p, k, has_temp))
    return rows


def _check_holds(rows, p) -> None:
    first: dict[int, tuple] = {}
    last_time = -math.inf
    backwards = sum(b[1] < a[1] for a, b in zip(rows, rows[1:]))
    shuffled = backwards > max(1.0, 0.1 * (len(rows) - 1))    # joined recordings go back once per join
    for k, t, step, rep, ph, ax, m, *_ in rows:
        if t < last_time and shuffled:
            raise RigError(f"the rows are not in time order: time goes backwards {backwards} times, first here ({t} "
                           f"after {last_time}); were they sorted by another column or shuffled? Sort the data rows "
                           f"by time_s (a recording is written in time order)", path=p, line=k, key="time_s")
        if t < last_time:
            raise RigError(f"time goes backwards ({t} after {last_time}): two recordings joined, or the clock reset? "
                           "Split the file at this line", path=p, line=k, key="time_s")
        last_time = t
        if step not in first:
            first[step] = (k, rep, ph, ax, m)
            continue
        k0, rep0, ph0, ax0, m0 = first[step]
        for name, a, b in (("mass_kg", m, m0), ("load_axis", ax, ax0), ("phase", ph, ph0), ("repeat", rep, rep0)):
            if a != b:
                raise RigError(f"{name} changes inside hold (step {step}): {b} at line {k0}, {a} here; every "
                               f"sample of a hold must share it", path=p, line=k, key=name)
    # every load axis's series starts with a mass-0 hold
    seen_axes: dict[LoadAxis, int] = {}
    for step, (k0, rep, ph, ax, m) in first.items():
        if ax not in seen_axes:
            seen_axes[ax] = step
            if m != 0.0:
                raise RigError(f"the series for load axis {ax.value} starts with mass {m} kg; it must start with "
                               f"a mass-0 hold (the unloaded reading)", path=p, line=k0, key="mass_kg")


def format_row(t: float, step: int, repeat: int, phase: Phase, axis: LoadAxis, mass: float,
               disp: tuple, temp: float | None, decimals: int = 4, force: float | None = None) -> str:
    """One sample line; ``temp`` / ``force`` None: no such column, NaN: an empty cell."""
    cells = [f"{t:.3f}", str(step), str(repeat), str(phase), str(axis), f"{mass:.4f}"]
    cells += ["" if (v is None or not math.isfinite(v)) else f"{round(v, decimals) + 0.0:.{decimals}f}" for v in disp]
    if temp is not None:
        cells.append("" if not math.isfinite(temp) else f"{temp:.2f}")
    if force is not None:
        cells.append("" if not math.isfinite(force) else f"{force:.4f}")
    return ",".join(cells) + "\n"


class RecordingWriter:
    """Append samples to a recording, flushed as they arrive; never rewrites what is on disk.

    Opening an existing file keeps every complete line; a torn last line (a crash mid-write) is cut off.
    ``fsync_every`` rows the file is fsync'ed (always on :meth:`close`). ``with_force``: a ``force_N`` column
    (a load cell). ``created``: the file was made by this writer (it did not exist or was empty); ``rows``: the
    samples written by it.
    """

    def __init__(self, path: str | Path, meta: dict, with_temp: bool = True, fsync_every: int = 50,
                 decimals: int = 4, with_force: bool = False) -> None:
        self.path = Path(path)
        self.decimals = decimals
        self.with_temp = with_temp
        self.with_force = with_force
        self.fsync_every = fsync_every
        self._since_sync = 0
        self.rows = 0
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.created = not (self.path.exists() and self.path.stat().st_size > 0)
        if not self.created:
            with open(self.path, "rb+") as fh:
                data = fh.read()
                cut = data.rfind(b"\n") + 1
                if cut < len(data):
                    fh.truncate(cut)
            self._fh = open(self.path, "a", encoding="utf-8", newline="")
        else:
            self._fh = open(self.path, "a", encoding="utf-8", newline="")
            head = io.StringIO()
            meta = dict(meta)
            meta.setdefault("format", FORMAT_RIG)
            for k in ("format", "rod"):
                if k in meta:
                    head.write(f"# {k}: {meta.pop(k)}\n")
            for k, v in meta.items():
                head.write(f"# {k}: {v}\n")
            head.write(",".join(COLUMNS + (("temp_C",) if with_temp else ()) + (("force_N",) if with_force else ()))
                       + "\n")
            self._fh.write(head.getvalue())
            self._sync()

    def write(self, t, step, repeat, phase, axis, mass, disp, temp=None, force=None) -> None:
        """One sample; ``force`` [N] the load cell's reading (None / NaN: an empty cell)."""
        f = (math.nan if force is None else float(force)) if self.with_force else None
        self._fh.write(format_row(t, step, repeat, Phase(phase), LoadAxis(axis), mass, disp,
                                  (math.nan if temp is None else temp) if self.with_temp else None, self.decimals, f))
        self._fh.flush()
        self.rows += 1
        self._since_sync += 1
        if self._since_sync >= self.fsync_every:
            self._sync()

    def comment(self, text: str) -> None:
        """Append a ``# text`` line (the reader skips comment lines among the samples)."""
        if "\n" in text:
            raise ValueError(f"a comment is one line, got {text!r}")
        self._fh.write(f"# {text}\n")
        self._fh.flush()

    def sync(self) -> None:
        """Flush and fsync what was written."""
        self._sync()

    def _sync(self) -> None:
        self._fh.flush()
        os.fsync(self._fh.fileno())
        self._since_sync = 0

    def close(self) -> None:
        if not self._fh.closed:
            self._sync()
            self._fh.close()

    def discard_if_empty(self) -> bool:
        """Close, and remove the file when this writer made it and wrote no sample into it (a run that failed
        before its first sample leaves no header-only file behind); True when removed."""
        self.close()
        if self.created and self.rows == 0:
            self.path.unlink(missing_ok=True)
            return True
        return False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
