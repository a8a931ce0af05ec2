"""Campaign and fixture files of the contract, read with line / key errors, and the CSV table reader the points
(validation) files share (:mod:`calibrate.points_file`).

- ``*.campaign.csv``: ``position,point,q1..qn,x_mm,y_mm,z_mm[,time_s][,temp_C]`` (q in deg; x, y, z the
  device's reading of the ball centre in {D_j}); or (v1.1) ``s1_mm,s2_mm,s3_mm``, the three sensors' raw
  readings, converted with a device file (:func:`calibrate.readings.apply_device`).
- ``*.fixture.json``: poses of {D_j} in {W} = {D_world_position}, the sensors' contact force in {D_j}.
"""
from __future__ import annotations

import csv
import logging
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.core.errors import did_you_mean
from rodlab.core.fileio import atomic_write_json, read_json, read_text_checked, separator_problem
from rodlab.core.frames import pose_to_matrix
from rodlab.core.schema import require_schema
from rodlab.core.schema_table import EMPTY_READING_FIX, READING_COLUMNS, decimal_comma_fix, sub_micrometre

from .errors import CalibrationError

__all__ = ["cell_number", "Campaign", "Fixture", "read_campaign", "read_fixture", "write_fixture", "FIXTURE_FORMATS"]

log = logging.getLogger(__name__)

#: fixture formats read; /2 adds each pose's covariance
FIXTURE_FORMATS = ("rodlab.fixture/1", "rodlab.fixture/2")
#: a contact force beyond this [N] per axis is a unit slip, not MultiCal's springs (about 1 N): warned of on reading
PLAUSIBLE_CONTACT_FORCE_N = 30.0
_WARNED_FORCES: set = set()


@dataclass
class Fixture:
    """Clamping positions: ``poses`` {j: pose of {D_j} in {W}, shape=(6,) [mm, deg]}; ``force_D_N`` shape=(3,);
    ``pose_cov`` {j: shape=(6, 6) covariance of pose j, (mm, deg) units} where stated (``rodlab.fixture/2``),
    else None; ``probing`` the free-form record of how the poses were measured."""

    poses: dict
    force_D_N: np.ndarray
    world_position: int
    path: Path | None = None
    pose_cov: dict | None = None
    probing: dict | None = None

    def transform(self, j: int) -> np.ndarray:
        return pose_to_matrix(self.poses[j])


@dataclass
class Campaign:
    """Rows of a campaign: position (N,), point (N,), q_deg (N, n), x_D_mm (N, 3) ball centre in {D_j} [mm]
    (None for raw readings not yet converted), time_s, temp_C (N,) or None; lines (N,) of the file.

    Raw campaigns (v1.1): readings_mm (N, 3) the sensors' readings [mm]; once converted with the device
    (:func:`calibrate.readings.apply_device`) also force_D_N (N, 3) the contact force of each point in {D_j} [N]
    (None: the fixture's constant one) and noise_shape_D (N, 3, 3) the covariance in {D_j} of a point per unit
    variance of each reading [-] (None: one noise level per coordinate)."""

    position: np.ndarray
    point: np.ndarray
    q_deg: np.ndarray
    x_D_mm: np.ndarray | None
    time_s: np.ndarray | None = None
    temp_C: np.ndarray | None = None
    path: Path | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))
    readings_mm: np.ndarray | None = None
    force_D_N: np.ndarray | None = None
    noise_shape_D: np.ndarray | None = None

    def __post_init__(self):
        for name in ("x_D_mm", "readings_mm", "force_D_N"):
            a = getattr(self, name)
            if a is not None and np.shape(a) != (self.n, 3):
                raise ValueError(f"{name} must have shape ({self.n}, 3), got {np.shape(a)}")
        if self.noise_shape_D is not None and np.shape(self.noise_shape_D) != (self.n, 3, 3):
            raise ValueError(f"noise_shape_D must have shape ({self.n}, 3, 3), got {np.shape(self.noise_shape_D)}")
        if self.x_D_mm is None and self.readings_mm is None:
            raise ValueError("a campaign needs x_D_mm or readings_mm")

    @property
    def raw(self) -> bool:
        """Whether the file gave the sensors' readings (s1_mm, s2_mm, s3_mm)."""
        return self.readings_mm is not None

    @property
    def n(self) -> int:
        return int(self.position.size)

    def labels(self) -> list[str]:
        return [f"{j}.{i}" for j, i in zip(self.position, self.point)]


def read_text_file(path) -> tuple[Path, str]:
    return Path(path), read_text_checked(path, CalibrationError)


def cell_number(cell, p, line: int, col: str) -> float:
    """A CSV cell as a finite number; :class:`CalibrationError` naming the file, line and column otherwise."""
    try:
        v = float(cell)
    except (TypeError, ValueError):
        fix = decimal_comma_fix(cell) if isinstance(cell, str) else None
        tail = f": a decimal comma (a locale's export); {fix}" if fix else ""
        if not tail and isinstance(cell, str) and not cell.strip():
            tail = f": {EMPTY_READING_FIX}" if col in READING_COLUMNS else ""
        raise CalibrationError(f"expected a number, got {cell!r}{tail}", path=p, line=line, key=col) from None
    if not math.isfinite(v):
        raise CalibrationError(f"expected a finite number, got {cell!r}", path=p, line=line, key=col)
    return v


def leading_comments(text: str) -> list[tuple[int, str, str]]:
    """The ``# key: value`` lines before a CSV header, as (line, key, value), both stripped; blank lines and
    comments without a colon are skipped."""
    out = []
    for k, line in enumerate(text.splitlines(), start=1):
        s = line.strip()
        if s and not s.startswith("#"):
            break
        body = s.lstrip("#").strip()
        if ":" in body:
            key, val = body.split(":", 1)
            out.append((k, key.strip(), val.strip()))
    return out


def read_table(p: Path, text: str, required: list[str], optional: list[str], text_columns: tuple = (),
               blank_nan: tuple = ()):
    """The header and the data rows ``(line, {column: number})`` of a CSV table (``text_columns`` kept as text;
    a blank cell of ``blank_nan`` is NaN, "not recorded", where any other blank cell is refused)."""
    lines = text.splitlines()
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        i += 1
    if i >= len(lines):
        raise CalibrationError("no header line", path=p)
    if (problem := separator_problem(lines[i])) is not None:
        raise CalibrationError(problem, path=p, line=i + 1)
    header = [h.strip() for h in next(csv.reader([lines[i]]))]
    allowed = required + optional
    _check_joint_columns(header, allowed, p, i + 1)
    for h in header:
        if h not in allowed:
            raise CalibrationError(f"unknown column {h!r}; expected {allowed}." + did_you_mean(h, allowed, units=True),
                                   path=p, line=i + 1, key=h)
    for h in required:
        if h not in header:
            raise CalibrationError(f"missing column {h!r}", path=p, line=i + 1, key=h)
    if len(set(header)) != len(header):
        raise CalibrationError("duplicated column", path=p, line=i + 1)
    rows = []
    for k, row in enumerate(csv.reader(lines[i + 1:]), start=i + 2):
        if not row or not "".join(row).strip() or row[0].lstrip().startswith("#"):
            continue
        if len(row) != len(header):
            raise CalibrationError(f"expected {len(header)} cells, got {len(row)}", path=p, line=k)
        rows.append((k, {h: _cell(c, p, k, h, text_columns, blank_nan) for h, c in zip(header, row)}))
    if not rows:
        raise CalibrationError("no data rows", path=p, line=i + 1)
    return header, rows


def _cell(c: str, p: Path, line: int, h: str, text_columns: tuple, blank_nan: tuple):
    if h in text_columns:
        return c.strip()
    if h in blank_nan and not c.strip():
        return math.nan
    return cell_number(c, p, line, h)


def _check_joint_columns(header: list[str], allowed: list[str], p: Path, line: int) -> None:
    """A file with another number of joint columns (q1..qm) than the robot model has joints: named as that, with
    the fix (the robot file), rather than as an unknown or missing column."""
    joint = re.compile(r"q([1-9][0-9]*)")
    have = sorted(int(m.group(1)) for h in header if (m := joint.fullmatch(h)))
    want = sorted(int(m.group(1)) for h in allowed if (m := joint.fullmatch(h)))
    if have and want and have != want and have == list(range(1, len(have) + 1)):
        missing = [f"q{k}" for k in want if k not in have]
        other = f"add the missing column(s) {', '.join(missing)}" if missing else "drop the extra joint columns"
        raise CalibrationError(f"the file has {len(have)} joint columns (q1..q{len(have)}) and the robot model "
                               f"{len(want)} joints: give the robot file of the robot that recorded it (--robot), or "
                               f"{other}", path=p, line=line, key=f"q{max(len(want), len(have))}")


XYZ_COLUMNS = ("x_mm", "y_mm", "z_mm")
#: v1.1: the three sensors' raw readings, instead of x, y, z (read with a device file)
RAW_COLUMNS = ("s1_mm", "s2_mm", "s3_mm")


def _campaign_columns(p: Path, text: str) -> tuple:
    """x, y, z or the raw readings, whichever set the header has (exactly one)."""
    first = next((ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")), "")
    header = [h.strip() for h in next(csv.reader([first]))] if first else []
    has_xyz = any(c in header for c in XYZ_COLUMNS)
    # raw readings in another unit (s1_um) are raw readings too: their unknown column is then told the conversion
    has_raw = any(c in header for c in RAW_COLUMNS) or (not has_xyz and any(re.fullmatch(r"s[1-3]_[a-z]+", c)
                                                                              for c in header))
    if has_raw and has_xyz:
        raise CalibrationError(f"give the ball centre ({', '.join(XYZ_COLUMNS)}) or the raw sensor readings "
                               f"({', '.join(RAW_COLUMNS)}), not both", path=p, key=RAW_COLUMNS[0])
    return RAW_COLUMNS if has_raw else XYZ_COLUMNS


def read_campaign(path, n_joints: int = 6, device=None) -> Campaign:
    """A campaign file; one of raw readings is converted with ``device`` (a :class:`~calibrate.device.Device`)
    when given, else kept as readings (``x_D_mm`` None: :func:`campaign_observations` then asks for it)."""
    p, text = read_text_file(path)
    qs = [f"q{i}" for i in range(1, n_joints + 1)]
    xyz = _campaign_columns(p, text)
    header, rows = read_table(p, text, ["position", "point"] + qs + list(xyz), ["time_s", "temp_C"])
    pos, pt, q, x, t, T, ln = [], [], [], [], [], [], []
    seen, copies = {}, {}
    for k, r in rows:
        for col in ("position", "point"):
            if r[col] != int(r[col]) or r[col] < 1:
                raise CalibrationError(f"expected a positive integer, got {r[col]:g}", path=p, line=k, key=col)
        key = (int(r["position"]), int(r["point"]))
        content = tuple(r[c] for c in qs + list(xyz))
        if key in seen:
            same = copies.get(content) == seen[key]
            raise CalibrationError(f"point {key[0]}.{key[1]} appears twice (also on line {seen[key]})" +
                                   ("; the rows are the same: delete the repeated one" if same else
                                    ": number every row uniquely"), path=p, line=k, key="point")
        if content in copies and sub_micrometre([r[c] for c in xyz]):
            raise CalibrationError(f"the row repeats line {copies[content]} in every joint angle and reading (a copy: a "
                                   "measurement repeated at the same pose reads differently by the device's noise); "
                                   "delete the copied rows", path=p, line=k, key="point")
        seen[key] = k
        copies.setdefault(content, k)
        pos.append(key[0])
        pt.append(key[1])
        q.append([r[c] for c in qs])
        x.append([r[c] for c in xyz])
        t.append(r.get("time_s", np.nan))
        T.append(r.get("temp_C", np.nan))
        ln.append(k)
    raw = xyz == RAW_COLUMNS
    camp = Campaign(np.array(pos), np.array(pt), np.array(q), None if raw else np.array(x),
                    np.array(t) if "time_s" in header else None, np.array(T) if "temp_C" in header else None,
                    p, np.array(ln), readings_mm=np.array(x) if raw else None)
    if device is not None:
        from .readings import apply_device   # cycle: readings imports Campaign and RAW_COLUMNS from here
        camp = apply_device(camp, device)
    return camp


def read_fixture(path) -> Fixture:
    p = Path(path)
    data, text = read_json(p, CalibrationError)
    if not isinstance(data, dict) or data.get("format") not in FIXTURE_FORMATS:
        raise CalibrationError(f"expected a JSON object with \"format\" one of {list(FIXTURE_FORMATS)}", path=p,
                               key="format")
    require_schema(data, data["format"], p, text, CalibrationError)       # keys, shapes, types
    poses = {int(k): np.asarray(v, dtype=float) for k, v in data["positions"].items()}
    for j, arr in poses.items():
        if not np.all(np.isfinite(arr)):                        # JSON's NaN / Infinity pass a number schema
            raise CalibrationError(f"expected a finite pose [x, y, z, a, b, c] (mm, deg), got {arr.tolist()}",
                                   path=p, key=f"positions.{j}")
    _refuse_metres(p, poses)
    wp = data["world_position"]
    if wp not in poses:
        raise CalibrationError(f"world_position must name one of the positions {sorted(poses)}, got {wp!r}",
                               path=p, key="world_position")
    fa = np.asarray(data.get("contact_force_N", [1.10, 1.25, 1.05]), dtype=float)
    if not np.all(np.isfinite(fa)):
        raise CalibrationError(f"expected 3 finite numbers [N], got {fa.tolist()}", path=p, key="contact_force_N")
    if np.abs(fa).max() > PLAUSIBLE_CONTACT_FORCE_N and (str(p), tuple(fa)) not in _WARNED_FORCES:
        _WARNED_FORCES.add((str(p), tuple(fa)))         # once per file, however often a command reads it
        log.warning("%s: contact_force_N %s: MultiCal's springs press the ball with about 1 N per axis; forces of "
                    "%.0f N would deflect the rod far beyond its calibration (a factor 100 or 1000 slipped in?)",
                    p, fa.tolist(), np.abs(fa).max())
    return Fixture(poses, fa, wp, p, _pose_covariances(p, data, poses), data.get("probing"))


#: clamping positions all within this distance of each other [mm] are in metres (a MultiCal fixture's lie hundreds
#: of mm apart: the paper's ring of positions around the robot; a trial's fixture file divided by 1000 was read as mm
#: and calibrated to 78 mm rms, 'not a noisier device')
FIXTURE_METRES_SPAN_MM = 2.0


#: ... the span a fixture's positions have in mm [mm]: read as metres they must span this (the paper's layout: about
#: 250 mm; the simulator's 1 and 5 share one place, 0.03 mm apart, the device turned: not metres)
FIXTURE_SPAN_MM = (50.0, 5000.0)


def _refuse_metres(p: Path, poses: dict) -> None:
    """Refuse two or more clamping positions whose translations all lie within :data:`FIXTURE_METRES_SPAN_MM` of
    each other and would span a fixture's :data:`FIXTURE_SPAN_MM` x 1000: metres where millimetres are expected."""
    xyz = np.array([np.asarray(v, float)[:3] for v in poses.values()])
    if len(xyz) < 2:
        return
    span = float(np.max(np.linalg.norm(xyz[:, None] - xyz[None], axis=2)))
    if span < FIXTURE_METRES_SPAN_MM and FIXTURE_SPAN_MM[0] <= 1000.0 * span <= FIXTURE_SPAN_MM[1]:
        raise CalibrationError(f"the clamping positions lie within {span:.4g} mm of each other (a MultiCal fixture's "
                               "lie tens to hundreds of mm apart): their x, y, z look like metres; the fixture's "
                               "positions are millimetres: multiply metres by 1000", path=p, key="positions")


def _pose_covariances(p: Path, data: dict, poses: dict) -> dict | None:
    """``pose_covariance`` of a fixture/2 file: symmetric, positive semi-definite, of a listed position."""
    if "pose_covariance" not in data:
        return None
    out = {}
    for k, v in data["pose_covariance"].items():
        key = f"pose_covariance.{k}"
        C = np.asarray(v, dtype=float)
        if int(k) not in poses:
            raise CalibrationError(f"position {k} is not among the positions {sorted(poses)}", path=p, key=key)
        if not np.all(np.isfinite(C)) or not np.allclose(C, C.T, rtol=1e-6, atol=1e-12):
            raise CalibrationError("expected a finite, symmetric 6x6 covariance [(mm, deg) units]", path=p, key=key)
        if np.linalg.eigvalsh(C).min() < -1e-9 * max(1.0, np.abs(C).max()):
            raise CalibrationError("the covariance has a negative eigenvalue: not a covariance", path=p, key=key)
        out[int(k)] = C
    return out


def write_fixture(fix: Fixture, path) -> Path:
    """Write ``fix`` atomically: ``rodlab.fixture/2`` when it has pose covariances, else ``rodlab.fixture/1``."""
    data = {"format": FIXTURE_FORMATS[1] if fix.pose_cov else FIXTURE_FORMATS[0], "world_position": fix.world_position,
            "positions": {str(j): [round(float(v), 6) for v in pose] for j, pose in sorted(fix.poses.items())},
            "contact_force_N": [float(v) for v in fix.force_D_N]}
    if fix.pose_cov:
        data["pose_covariance"] = {str(j): [[float(f"{v:.6g}") for v in row] for row in C]
                                   for j, C in sorted(fix.pose_cov.items())}
    if fix.probing:
        data["probing"] = fix.probing
    return atomic_write_json(path, data)
