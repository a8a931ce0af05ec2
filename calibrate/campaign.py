"""Campaign, fixture and validation files of the contract, read with line / key errors.

- ``*.campaign.csv``: ``position,point,q1..qn,x_mm,y_mm,z_mm[,time_s][,temp_C]`` (q in deg; x, y, z the
  device's reading of the ball centre in {D_j}).
- ``*.fixture.json``: poses of {D_j} in {W} = {D_world_position}, the sensors' contact force in {D_j}.
- ``*.validation.csv``: ``# tool_mm``, ``# rod_mass_kg``, ``# rod_com_T_mm``, ``[# temp_C]`` then
  ``q1..qn,x_mm,y_mm,z_mm`` (ball centre in {W} from an external instrument).
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.errors import did_you_mean
from rodlab.fileio import read_text_checked
from rodlab.frames import pose_to_matrix

from .errors import CalibrationError

__all__ = ["Campaign", "Fixture", "PointSet", "read_campaign", "read_fixture", "read_points"]


@dataclass
class Fixture:
    """Clamping positions: ``poses`` {j: pose of {D_j} in {W}, shape=(6,) [mm, deg]}; ``force_D_N`` shape=(3,)."""

    poses: dict
    force_D_N: np.ndarray
    world_position: int
    path: Path | None = None

    def transform(self, j: int) -> np.ndarray:
        return pose_to_matrix(self.poses[j])


@dataclass
class Campaign:
    """Rows of a campaign: position (N,), point (N,), q_deg (N, n), x_D_mm (N, 3), time_s, temp_C (N,) or None."""

    position: np.ndarray
    point: np.ndarray
    q_deg: np.ndarray
    x_D_mm: np.ndarray
    time_s: np.ndarray | None = None
    temp_C: np.ndarray | None = None
    path: Path | None = None
    lines: np.ndarray = field(default_factory=lambda: np.zeros(0, int))

    @property
    def n(self) -> int:
        return int(self.position.size)

    def labels(self) -> list[str]:
        return [f"{j}.{i}" for j, i in zip(self.position, self.point)]


@dataclass
class PointSet:
    """Ball centres measured in {W} by an external instrument (validation-file format)."""

    q_deg: np.ndarray
    x_W_mm: np.ndarray
    tool_mm: np.ndarray
    rod_mass_kg: float
    rod_com_T_mm: np.ndarray
    temp_C: float | None = None
    path: Path | None = None
    sigma_mm: np.ndarray | None = None      # (N, 3) stated standard uncertainty of each coordinate [mm], optional

def _read_text(path) -> tuple[Path, str]:
    return Path(path), read_text_checked(path, CalibrationError)


def _num(cell, p, line, col):
    try:
        v = float(cell)
    except (TypeError, ValueError):
        raise CalibrationError(f"expected a number, got {cell!r}", path=p, line=line, key=col) from None
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


def _table(p: Path, text: str, required: list[str], optional: list[str]):
    lines = text.splitlines()
    i = 0
    while i < len(lines) and (not lines[i].strip() or lines[i].lstrip().startswith("#")):
        i += 1
    if i >= len(lines):
        raise CalibrationError("no header line", path=p)
    header = [h.strip() for h in next(csv.reader([lines[i]]))]
    allowed = required + optional
    for h in header:
        if h not in allowed:
            raise CalibrationError(f"unknown column {h!r}; expected {allowed}." + did_you_mean(h, allowed), path=p,
                                   line=i + 1, key=h)
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
        rows.append((k, {h: _num(c, p, k, h) for h, c in zip(header, row)}))
    if not rows:
        raise CalibrationError("no data rows", path=p, line=i + 1)
    return header, rows


def read_campaign(path, n_joints: int = 6) -> Campaign:
    p, text = _read_text(path)
    qs = [f"q{i}" for i in range(1, n_joints + 1)]
    header, rows = _table(p, text, ["position", "point"] + qs + ["x_mm", "y_mm", "z_mm"], ["time_s", "temp_C"])
    pos, pt, q, x, t, T, ln = [], [], [], [], [], [], []
    seen = {}
    for k, r in rows:
        for col in ("position", "point"):
            if r[col] != int(r[col]) or r[col] < 1:
                raise CalibrationError(f"expected a positive integer, got {r[col]:g}", path=p, line=k, key=col)
        key = (int(r["position"]), int(r["point"]))
        if key in seen:
            raise CalibrationError(f"point {key[0]}.{key[1]} appears twice (also on line {seen[key]})", path=p,
                                   line=k, key="point")
        seen[key] = k
        pos.append(key[0])
        pt.append(key[1])
        q.append([r[c] for c in qs])
        x.append([r["x_mm"], r["y_mm"], r["z_mm"]])
        t.append(r.get("time_s", np.nan))
        T.append(r.get("temp_C", np.nan))
        ln.append(k)
    return Campaign(np.array(pos), np.array(pt), np.array(q), np.array(x),
                    np.array(t) if "time_s" in header else None, np.array(T) if "temp_C" in header else None,
                    p, np.array(ln))


def read_fixture(path) -> Fixture:
    p, text = _read_text(path)
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise CalibrationError(f"not valid JSON: {e.msg}", path=p, line=e.lineno) from e
    if not isinstance(data, dict) or data.get("format") != "rodlab.fixture/1":
        raise CalibrationError("expected a JSON object with \"format\": \"rodlab.fixture/1\"", path=p, key="format")
    from rodlab.schema import require_schema
    require_schema(data, "rodlab.fixture/1", p, text, CalibrationError)       # keys, shapes, types
    poses = {int(k): np.asarray(v, dtype=float) for k, v in data["positions"].items()}
    for j, arr in poses.items():
        if not np.all(np.isfinite(arr)):                        # JSON's NaN / Infinity pass a number schema
            raise CalibrationError(f"expected a finite pose [x, y, z, a, b, c] (mm, deg), got {arr.tolist()}",
                                   path=p, key=f"positions.{j}")
    wp = data["world_position"]
    if wp not in poses:
        raise CalibrationError(f"world_position must name one of the positions {sorted(poses)}, got {wp!r}",
                               path=p, key="world_position")
    fa = np.asarray(data.get("contact_force_N", [1.10, 1.25, 1.05]), dtype=float)
    if not np.all(np.isfinite(fa)):
        raise CalibrationError(f"expected 3 finite numbers [N], got {fa.tolist()}", path=p, key="contact_force_N")
    return Fixture(poses, fa, wp, p)


def read_points(path, n_joints: int = 6) -> PointSet:
    p, text = _read_text(path)
    meta = {key: (k, val) for k, key, val in leading_comments(text)}
    def vec(key, n):
        if key not in meta:
            raise CalibrationError(f"missing comment line '# {key}: ...'", path=p, line=1, key=key)
        k, val = meta[key]
        try:
            arr = np.array([float(v) for v in val.split(",")])
        except ValueError:
            raise CalibrationError(f"expected {n} comma-separated numbers, got {val!r}", path=p, line=k,
                                   key=key) from None
        if arr.size != n or not np.all(np.isfinite(arr)):
            raise CalibrationError(f"expected {n} finite numbers, got {val!r}", path=p, line=k, key=key)
        return arr
    tool = vec("tool_mm", 3)
    mass = float(vec("rod_mass_kg", 1)[0]) if "rod_mass_kg" in meta else 0.0
    com = vec("rod_com_T_mm", 3) if "rod_com_T_mm" in meta else np.zeros(3)
    temp = float(vec("temp_C", 1)[0]) if "temp_C" in meta else None
    qs = [f"q{i}" for i in range(1, n_joints + 1)]
    header, rows = _table(p, text, qs + ["x_mm", "y_mm", "z_mm"], list(SIGMA_COLUMNS))
    q = np.array([[r[c] for c in qs] for _, r in rows])
    x = np.array([[r["x_mm"], r["y_mm"], r["z_mm"]] for _, r in rows])
    return PointSet(q, x, tool, mass, com, temp, p, _point_sigmas(p, header, rows))


#: optional per-point uncertainty columns of a points file: one standard deviation per coordinate [mm]
SIGMA_COLUMNS = ("sigma_x_mm", "sigma_y_mm", "sigma_z_mm")


def _point_sigmas(p: Path, header: list[str], rows) -> np.ndarray | None:
    """The per-point uncertainties (N, 3) [mm], all three columns or none, each > 0."""
    present = [c for c in SIGMA_COLUMNS if c in header]
    if not present:
        return None
    if len(present) != 3:
        missing = [c for c in SIGMA_COLUMNS if c not in header]
        raise CalibrationError(f"per-point uncertainty needs all of {list(SIGMA_COLUMNS)}; missing {missing}. Add "
                               f"them or drop {present}", path=p, key=missing[0])
    for k, r in rows:
        for c in SIGMA_COLUMNS:
            if not r[c] > 0:
                raise CalibrationError(f"expected a standard deviation > 0 [mm], got {r[c]:g}", path=p, line=k, key=c)
    return np.array([[r[c] for c in SIGMA_COLUMNS] for _, r in rows])
