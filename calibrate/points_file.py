"""Points measured by an external instrument (a laser tracker, a CMM): the contract's validation-file format
(``*.validation.csv``, format ``rodlab.points/1``), read with line / key errors.

``# tool_mm``, ``# rod_mass_kg``, ``# rod_com_T_mm``, ``[# temp_C]`` then ``q1..qn,x_mm,y_mm,z_mm`` (ball centre in
{W}) and the optional columns of a tracker's export: ``sigma_x_mm,sigma_y_mm,sigma_z_mm`` (one standard deviation
per coordinate), ``name``/``point_name``/``label``/``timestamp``/``date`` (text, kept), ``time_s`` and ``temp_C``
(the time and temperature of each point). A blank ``time_s`` or ``temp_C`` cell is a point whose time or
temperature was not recorded (a tracker's export leaves the cell empty where its weather station dropped out),
not an error: the rest of the file is read and the column's missing values are NaN.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from .campaign import leading_comments, read_table, read_text_file
from .errors import CalibrationError
from .rod import Rod
from .units_line import units_line_problem

__all__ = ["PointSet", "read_points", "SIGMA_COLUMNS", "POINT_TEXT", "POINT_EXTRAS", "POINT_OPTIONAL_NUMBERS",
           "NAME_COLUMNS"]

#: optional per-point uncertainty columns of a points file: one standard deviation per coordinate [mm]
SIGMA_COLUMNS = ("sigma_x_mm", "sigma_y_mm", "sigma_z_mm")
#: optional text columns of a tracker's export: name or label, time stamp (kept, not read)
POINT_TEXT = ("name", "point_name", "label", "timestamp", "date")
#: the text columns that name a point, in the order one is taken
NAME_COLUMNS = ("name", "point_name", "label")
#: optional number columns whose blank cells mean "not recorded" (NaN): time [s] and temperature [degC]
POINT_OPTIONAL_NUMBERS = ("time_s", "temp_C")
POINT_EXTRAS = (*POINT_TEXT, *POINT_OPTIONAL_NUMBERS)


@dataclass
class PointSet:
    """Ball centres measured in {W} by an external instrument (validation-file format).

    q_deg (N, n) joint angles [deg]; x_W_mm (N, 3) ball centre in {W} [mm]; tool_mm (3,) ball centre in the
    flange frame {T} [mm]; rod_mass_kg [kg] and rod_com_T_mm (3,) [mm, {T}] the probe's payload; temp_C the
    file's one temperature [degC] (``# temp_C``) or None; sigma_mm (N, 3) the stated standard uncertainty of each
    coordinate [mm] or None; temp_each_C and time_each_s (N,) the temperature [degC] and time [s] of each point
    (a ``temp_C`` / ``time_s`` column; NaN where a cell was blank) or None; names (N,) each point's name from a
    ``name``, ``point_name`` or ``label`` column (the first the file has) or None."""

    q_deg: np.ndarray
    x_W_mm: np.ndarray
    tool_mm: np.ndarray
    rod_mass_kg: float
    rod_com_T_mm: np.ndarray
    temp_C: float | None = None
    path: Path | None = None
    sigma_mm: np.ndarray | None = None
    temp_each_C: np.ndarray | None = None
    time_each_s: np.ndarray | None = None
    names: tuple | None = None

    def __post_init__(self):
        n = np.shape(self.q_deg)[0]
        if np.shape(self.x_W_mm) != (n, 3):
            raise ValueError(f"x_W_mm must have shape ({n}, 3), got {np.shape(self.x_W_mm)}")
        for name in ("temp_each_C", "time_each_s", "names"):
            a = getattr(self, name)
            if a is not None and np.shape(a) != (n,):
                raise ValueError(f"{name} must have shape ({n},), got {np.shape(a)}")
        if self.sigma_mm is not None and np.shape(self.sigma_mm) != (n, 3):
            raise ValueError(f"sigma_mm must have shape ({n}, 3), got {np.shape(self.sigma_mm)}")

    def subset(self, idx) -> PointSet:
        """The points selected by the boolean or index array ``idx``, each per-point column with them."""
        def cut(a):
            return None if a is None else a[idx]
        return replace(self, q_deg=self.q_deg[idx], x_W_mm=self.x_W_mm[idx], sigma_mm=cut(self.sigma_mm),
                       temp_each_C=cut(self.temp_each_C), time_each_s=cut(self.time_each_s),
                       names=None if self.names is None else tuple(np.asarray(self.names, object)[idx]))

    @property
    def rod(self) -> Rod:
        """The instrument's rigid probe as a calibration takes it: the file's ``tool_mm`` and its payload
        (``rod_mass_kg``, ``rod_com_T_mm``)."""
        return Rod.rigid(self.tool_mm, self.rod_mass_kg, self.rod_com_T_mm)


def read_points(path, n_joints: int = 6) -> PointSet:
    """A points (validation) file of a robot with ``n_joints`` joints; :class:`CalibrationError` naming the file,
    line and key of the first problem."""
    p, text = read_text_file(path)
    meta = {key: (k, val) for k, key, val in leading_comments(text)}
    _check_units_lines(p, meta)
    tool = _meta_numbers(p, meta, "tool_mm", 3)
    mass = float(_meta_numbers(p, meta, "rod_mass_kg", 1)[0]) if "rod_mass_kg" in meta else 0.0
    com = _meta_numbers(p, meta, "rod_com_T_mm", 3) if "rod_com_T_mm" in meta else np.zeros(3)
    temp = float(_meta_numbers(p, meta, "temp_C", 1)[0]) if "temp_C" in meta else None
    qs = [f"q{i}" for i in range(1, n_joints + 1)]
    header, rows = read_table(p, text, qs + ["x_mm", "y_mm", "z_mm"], list(SIGMA_COLUMNS) + list(POINT_EXTRAS),
                              text_columns=POINT_TEXT, blank_nan=POINT_OPTIONAL_NUMBERS)
    q = np.array([[r[c] for c in qs] for _, r in rows])
    x = np.array([[r["x_mm"], r["y_mm"], r["z_mm"]] for _, r in rows])
    each = {c: np.array([r[c] for _, r in rows]) if c in header else None for c in POINT_OPTIONAL_NUMBERS}
    named = next((c for c in NAME_COLUMNS if c in header), None)
    names = tuple(r[named] for _, r in rows) if named else None
    return PointSet(q, x, tool, mass, com, temp, p, _point_sigmas(p, header, rows), each["temp_C"], each["time_s"],
                    names)


def _check_units_lines(p: Path, meta: dict) -> None:
    for key, (k, val) in meta.items():
        if key.lower() in ("unit", "units") and (problem := units_line_problem(val)):
            raise CalibrationError(problem, path=p, line=k, key=key)


def _meta_numbers(p: Path, meta: dict, key: str, n: int) -> np.ndarray:
    """The ``# key: a, b, c`` line's ``n`` finite numbers."""
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
