"""Robot files in TOML (``rodlab.robot/1`` and ``/2``): DH or modified-DH (Craig) rows, limits, link masses.

``rodlab.robot/1``: the calibrator's own rows (DH with Hayati's ``beta_deg``), read as they are.
``rodlab.robot/2`` adds ``convention = "dh" | "mdh"`` (default ``"dh"``), ``source`` (where the numbers come
from), ``flange_pose`` (the flange in the last row's frame [mm, deg], default zeros) and a joint ``name``:

- ``dh``  (classic): ``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) [Ry(beta_i)]``, joint i about
  ``z_{i-1}``; rows are used as they are, except that a ``flange_pose`` is folded into the last row (its
  ``theta_offset``, ``d``, ``a``, ``alpha``, ``beta`` and ``com_mm``) so that ``{n}`` is the flange frame, in
  which tool vectors and a rod's matrices are given (exact; a flange off the last axis keeps the rest in
  ``n_T_tip``);
- ``mdh`` (Craig): ``T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)``, joint i about ``z_i``;
  row i holds ``alpha_deg = alpha_{i-1}``, ``a_mm = a_{i-1}``, ``theta_offset_deg``, ``d_mm`` and ``com_mm``
  in frame i (at joint i). Converted exactly to the calibrator's rows through the joint axes
  (:mod:`calibrate.robot_lines`).
Errors name the file, line and key.
"""
from __future__ import annotations

import logging

import re
import sys
from pathlib import Path

import numpy as np

from rodlab.core.errors import did_you_mean
from rodlab.core.fileio import toml_problem
from rodlab.core.frames import pose_to_matrix
from rodlab.core.schema import require_schema

from .errors import CalibrationError
from .robot import Robot, robot_from_chain
from .robot_lines import ZeroChain, chain_matrices, end_row, row_matrix
from .robot_reader import RobotFormat

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

log = logging.getLogger(__name__)

__all__ = ["read_robot_toml", "row_key_line", "FORMAT_ROBOT", "FORMATS_ROBOT", "CONVENTIONS", "ROBOT_FORMAT"]

FORMAT_ROBOT = "rodlab.robot/2"
FORMATS_ROBOT = ("rodlab.robot/1", "rodlab.robot/2")
CONVENTIONS = ("dh", "mdh")
_ROW_KEYS = ("theta_offset_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg", "limits_deg", "mass_kg", "com_mm")
_DEFAULTS = {"beta_deg": 0.0, "theta_offset_deg": 0.0, "limits_deg": [-180.0, 180.0], "mass_kg": 0.0,
             "com_mm": [0.0, 0.0, 0.0]}
_TOP_KEYS = ("format", "name", "gravity_base", "joint", "convention", "source", "flange_pose")


def _line(text, idx, key):
    """Line of ``key`` in the ``idx``-th ``[[joint]]`` table (or at the top level for ``idx = None``)."""
    count = -1
    for i, raw in enumerate(text.splitlines(), start=1):
        if raw.strip().startswith("[[joint]]"):
            count += 1
        if (count == idx or (idx is None and count == -1)) and re.match(rf"^\s*{key}\s*=", raw):
            return i
    return None


#: a geometric parameter's kind -> its key in a joint table
ROW_KEYS = {"d": "d_mm", "a": "a_mm", "alpha": "alpha_deg", "beta": "beta_deg", "dtheta": "theta_offset_deg"}


def row_key_line(path, joint: int, kind: str) -> int | None:
    """The line of joint ``joint``'s (0-based) ``kind`` key (``d``, ``a``, ``alpha``, ``beta``, ``dtheta``) in the
    robot TOML file ``path``; None for another kind of file, an unreadable one or a key the table leaves to its
    default."""
    p = Path(path)
    if p.suffix.lower() != ".toml" or kind not in ROW_KEYS:
        return None
    try:
        text = p.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    return _line(text, joint, ROW_KEYS[kind])


def _load(p: Path) -> tuple[str, dict]:
    try:
        text = p.read_text(encoding="utf-8")
        return text, tomllib.loads(text)
    except FileNotFoundError as e:
        raise CalibrationError("file not found", path=p) from e
    except (OSError, UnicodeDecodeError) as e:
        raise CalibrationError(f"cannot read: {e}", path=p) from e
    except tomllib.TOMLDecodeError as e:
        message, line = toml_problem(e, text)
        raise CalibrationError(message, path=p, line=line) from e


def _numbers(v, shape, where) -> np.ndarray:
    items = v if isinstance(v, list) else [v]
    ok = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in items)
    arr = np.asarray(v, dtype=float) if ok else None
    if arr is None or arr.shape != shape or not np.all(np.isfinite(arr)):
        raise CalibrationError(f"expected {'a number' if not shape else f'{shape[0]} numbers'}, got {v!r}", **where)
    return arr


def _header(p: Path, text: str, data: dict) -> tuple[str, str]:
    fmt = data.get("format")
    if fmt not in FORMATS_ROBOT:
        raise CalibrationError(f"expected format = \"{FORMAT_ROBOT}\" (or \"{FORMATS_ROBOT[0]}\"), got {fmt!r}",
                               path=p, key="format", line=_line(text, None, "format"))
    for k in data:
        if k not in _TOP_KEYS:
            raise CalibrationError("unknown key." + did_you_mean(k, _TOP_KEYS), path=p, key=k,
                                   line=_line(text, None, k))
    convention = data.get("convention", "dh")
    if fmt == FORMATS_ROBOT[0] and any(k in data for k in ("convention", "source", "flange_pose")):
        raise CalibrationError(f"`convention`, `source` and `flange_pose` need format = \"{FORMAT_ROBOT}\"", path=p,
                               key="format", line=_line(text, None, "format"))
    if convention not in CONVENTIONS:
        raise CalibrationError(f"expected one of {list(CONVENTIONS)}, got {convention!r}", path=p,
                               key="convention", line=_line(text, None, "convention"))
    return convention, str(data.get("source", ""))


def _joint_rows(p: Path, text: str, joints, convention: str) -> tuple[dict, list]:
    if not isinstance(joints, list) or len(joints) < 2:
        raise CalibrationError("expected at least two [[joint]] tables", path=p, key="joint")
    cols, names = {k: [] for k in _ROW_KEYS}, []
    for i, j in enumerate(joints):
        for k in j:
            if k not in _ROW_KEYS + ("name",):
                raise CalibrationError(f"unknown key in joint {i + 1}." + did_you_mean(k, _ROW_KEYS + ("name",)),
                                       path=p, line=_line(text, i, k), key=f"joint[{i + 1}].{k}")
        if convention == "mdh" and j.get("beta_deg", 0.0) != 0.0:
            raise CalibrationError("beta_deg is not part of the modified-DH convention; give the rows in "
                                   "convention = \"dh\" to use Hayati's beta", path=p,
                                   line=_line(text, i, "beta_deg"), key=f"joint[{i + 1}].beta_deg")
        names.append(str(j.get("name", f"joint_{i + 1}")))
        for k in _ROW_KEYS:
            cols[k].append(_row_value(p, text, i, k, j.get(k, _DEFAULTS.get(k))))
    return {k: np.array(v) for k, v in cols.items()}, names


def _row_value(p, text, i, k, v) -> np.ndarray:
    where = {"path": p, "line": _line(text, i, k), "key": f"joint[{i + 1}].{k}"}
    if v is None:
        raise CalibrationError(f"joint {i + 1} needs `{k}`", path=p, key=f"joint[{i + 1}].{k}")
    arr = _numbers(v, {"limits_deg": (2,), "com_mm": (3,)}.get(k, ()), where)
    if k == "limits_deg" and not arr[0] < arr[1]:
        raise CalibrationError(f"limits must be [lower, upper] with lower < upper, got {v}", **where)
    if k == "mass_kg" and arr < 0:
        raise CalibrationError("mass must be >= 0", **where)
    return arr


def _gravity(p, text, data) -> np.ndarray:
    where = {"path": p, "key": "gravity_base", "line": _line(text, None, "gravity_base")}
    g = _numbers(data.get("gravity_base", [0.0, 0.0, -9.80665]), (3,), where)
    if np.linalg.norm(g) == 0:
        raise CalibrationError("gravity_base must be 3 finite numbers [m/s^2], not all zero", **where)
    return g


def _mdh_chain(name, cols, flange_T, gravity, source) -> ZeroChain:
    """Frames of the modified-DH rows at q = 0: joint i turns about z_i through o_i."""
    n = len(cols["d_mm"])
    T, frames = np.eye(4), []
    for i in range(n):                                  # Rx(alpha) Tx(a) = Tx(a) Rx(alpha): one pose each
        T = T @ pose_to_matrix([cols["a_mm"][i], 0, 0, cols["alpha_deg"][i], 0, 0]) \
              @ pose_to_matrix([0, 0, cols["d_mm"][i], 0, 0, cols["theta_offset_deg"][i]])
        frames.append(T)
    F = np.array(frames)
    com = np.einsum("nij,nj->ni", F, np.c_[cols["com_mm"], np.ones(n)])[:, :3]
    return ZeroChain(name, F[:, :3, 3].copy(), F[:, :3, 2].copy(), F[-1] @ flange_T, cols["limits_deg"],
                     cols["mass_kg"], com, gravity, source)


def read_robot_toml(path) -> Robot:
    """Read a robot TOML file (see the module docstring); errors name the file, line and key."""
    p = Path(path)
    text, data = _load(p)
    convention, source = _header(p, text, data)
    cols, names = _joint_rows(p, text, data.get("joint"), convention)
    _refuse_radians_and_metres(p, text, cols)
    for problem in unit_slips(cols):
        log.warning("%s: %s", p, problem)
    gravity = _gravity(p, text, data)
    flange = pose_to_matrix(_numbers(data.get("flange_pose", [0.0] * 6), (6,),
                                     {"path": p, "key": "flange_pose", "line": _line(text, None, "flange_pose")}))
    name = str(data.get("name", p.stem))
    require_schema(data, "rodlab.robot/2", p, text, CalibrationError, kind="toml")    # anything the rules above miss
    if convention == "mdh":
        return robot_from_chain(_mdh_chain(name, cols, flange, gravity, source or str(p)), names, path=p)
    cols, n_T_tip = _end_on_flange(cols, flange)
    return Robot(name, *(cols[k] for k in _ROW_KEYS), gravity_base=gravity, path=p, n_T_tip=n_T_tip,
                 joint_names=tuple(names), source=source or str(p))


#: no industrial arm's link offset or length exceeds this [mm] ...
LINK_MAX_MM = 5000.0
#: ... and every arm has one at least this long [mm] (a file whose longest is shorter is in metres)
LINK_MIN_MM = 5.0


#: twists or offsets at +-pi/2 or +-pi as numbers on this many joints are radians, not a robot: refused
RADIAN_JOINTS = 2


def _radian_joints(values) -> list[int]:
    """1-based joints whose value is +-pi/2 or +-pi as a number (to 1e-3)."""
    v = np.abs(np.asarray(values, float))
    return [i + 1 for i, x in enumerate(v) if min(abs(x - np.pi / 2), abs(x - np.pi)) < 1e-3]


def _refuse_radians_and_metres(p: Path, text: str, cols: dict) -> None:
    """Refuse DH rows no arm has: twists or offsets at +-pi/2 or +-pi on :data:`RADIAN_JOINTS` joints or more
    (radians where degrees are expected; an IRB 4600 trial's file with alpha -1.5708 had been read with a warning
    and calibrated to 590 mm rms), or every length below :data:`LINK_MIN_MM` (metres). Errors name the first
    joint's line and key, and the fix."""
    for key in ("alpha_deg", "theta_offset_deg"):
        rad = _radian_joints(cols[key])
        if len(rad) >= RADIAN_JOINTS:
            raise CalibrationError(f"{key} of joints {rad} is +-pi/2 or +-pi as a number ("
                                   f"{', '.join(f'{cols[key][i - 1]:.4f}' for i in rad)}): radians where degrees are "
                                   "expected; write the angles in degrees (90, -90, 180)", path=p,
                                   line=_line(text, rad[0] - 1, key), key=f"joint[{rad[0]}].{key}")
    lengths = np.abs(np.concatenate([np.asarray(cols["d_mm"], float), np.asarray(cols["a_mm"], float)]))
    if 0 < lengths.max() < LINK_MIN_MM:
        raise CalibrationError(f"every d_mm and a_mm is below {LINK_MIN_MM:g} mm (longest {lengths.max():.4g}): metres "
                               "where millimetres are expected; multiply them by 1000", path=p, key="joint[1].d_mm",
                               line=_line(text, 0, "d_mm"))


def unit_slips(cols: dict) -> list[str]:
    """Numbers of DH rows no arm has, each with the slip that gives them: twists or offsets at +-pi/2 or +-pi
    (radians where degrees are expected), every length below :data:`LINK_MIN_MM` (metres), a length beyond
    :data:`LINK_MAX_MM`. Empty when none."""
    out = []
    for key in ("alpha_deg", "theta_offset_deg"):
        v = np.abs(np.asarray(cols[key], float))
        rad = _radian_joints(v)
        if rad:
            out.append(f"{key} of joint(s) {rad} is +-pi/2 or +-pi as a number ({', '.join(f'{v[i - 1]:.4f}' for i in rad)}): "
                       "radians where degrees are expected? write 90 or 180")
    lengths = np.abs(np.concatenate([np.asarray(cols["d_mm"], float), np.asarray(cols["a_mm"], float)]))
    if lengths.max() < LINK_MIN_MM and lengths.max() > 0:
        out.append(f"every d_mm and a_mm is below {LINK_MIN_MM:g} mm (longest {lengths.max():.4g}): metres where "
                   "millimetres are expected? multiply by 1000")
    if lengths.max() > LINK_MAX_MM:
        out.append(f"a d_mm or a_mm of {lengths.max():.6g} mm: beyond any industrial arm ({LINK_MAX_MM:g} mm): a typo "
                   "or another unit?")
    return out


def _end_on_flange(cols: dict, flange_T: np.ndarray) -> tuple[dict, np.ndarray]:
    """DH rows with the flange folded into the last row (``{n}`` = the flange frame when the flange's z lies on
    the last axis) and what is left of the flange in the new {n}; the rows unchanged without a flange."""
    if np.allclose(flange_T, np.eye(4), rtol=0.0, atol=1e-12):
        return cols, np.eye(4)
    F = chain_matrices(cols["theta_offset_deg"], cols["d_mm"], cols["a_mm"], cols["alpha_deg"], cols["beta_deg"])
    row, _ = end_row(F[-2], F[-1] @ flange_T)
    new_T_old = np.linalg.inv(F[-2] @ row_matrix(*row)) @ F[-1]      # the old {n} in the new one
    out = {k: np.array(v, float) for k, v in cols.items()}
    for k, v in zip(("theta_offset_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg"),
                    (np.degrees(row[0]), row[1], row[2], np.degrees(row[3]), np.degrees(row[4]))):
        out[k][-1] = v
    out["com_mm"][-1] = (new_T_old @ np.r_[out["com_mm"][-1], 1.0])[:3]
    return out, new_T_old @ flange_T


def _read(path, base_link=None, tip_link=None) -> Robot:
    if base_link or tip_link:
        raise CalibrationError("--base-link / --tip-link choose a chain in a URDF; a TOML robot file is one chain",
                               path=path, key="base_link" if base_link else "tip_link")
    return read_robot_toml(path)


#: robot TOML files in the registry (:data:`rodlab.calibrate.robot_formats.ROBOT_READERS`)
ROBOT_FORMAT = RobotFormat(_read, "a robot TOML file (DH or modified-DH rows)", suffix=".toml")
