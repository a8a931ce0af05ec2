"""Robot files (contract ``rodlab.robot/1``): DH rows with Hayati's beta, joint limits, link masses.

``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)``, ``theta_i = q_i + theta_offset_i``;
link i's mass and centre of mass (in frame i, at the end of the link) feed the static joint torques.
"""
from __future__ import annotations

import math
import re
import sys
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path

import numpy as np

from rodlab.errors import did_you_mean

from .errors import CalibrationError

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Robot", "read_robot", "resolve_robot", "FORMAT_ROBOT"]

FORMAT_ROBOT = "rodlab.robot/1"
_JOINT_KEYS = ("theta_offset_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg", "limits_deg", "mass_kg", "com_mm")


@dataclass(frozen=True)
class Robot:
    """A serial robot.

    Attributes (n = number of joints)
    ---------------------------------
    name; theta_offset_deg, d_mm, a_mm, alpha_deg, beta_deg : shape=(n,) nominal DH rows [deg, mm]
    limits_deg : shape=(n, 2); mass_kg : shape=(n,); com_mm : shape=(n, 3) in frame i
    gravity_base : shape=(3,) [m/s^2] in {0}
    """

    name: str
    theta_offset_deg: np.ndarray
    d_mm: np.ndarray
    a_mm: np.ndarray
    alpha_deg: np.ndarray
    beta_deg: np.ndarray
    limits_deg: np.ndarray
    mass_kg: np.ndarray
    com_mm: np.ndarray
    gravity_base: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.80665]))
    path: Path | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        n = self.n
        for k in ("d_mm", "a_mm", "alpha_deg", "beta_deg", "mass_kg"):
            if np.shape(getattr(self, k)) != (n,):
                raise ValueError(f"{k} must have shape ({n},)")
        if np.shape(self.limits_deg) != (n, 2) or np.shape(self.com_mm) != (n, 3):
            raise ValueError("limits_deg must be (n, 2) and com_mm (n, 3)")

    @property
    def n(self) -> int:
        return int(np.shape(self.theta_offset_deg)[0])

    def parallel_rows(self) -> list[int]:
        """Rows (0-based) whose joint axis is parallel to the next one (alpha = 0, next row exists)."""
        return [i for i in range(self.n - 1) if abs(math.remainder(self.alpha_deg[i], 180.0)) < 1e-6]


def _line(text, idx, key):
    count = -1
    for i, raw in enumerate(text.splitlines(), start=1):
        if raw.strip().startswith("[[joint]]"):
            count += 1
        if count == idx and re.match(rf"^\s*{key}\s*=", raw):
            return i
    return None


def read_robot(path) -> Robot:
    """Read a contract robot file (errors name the file, line and key)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except FileNotFoundError as e:
        raise CalibrationError("file not found", path=p) from e
    except (OSError, UnicodeDecodeError) as e:
        raise CalibrationError(f"cannot read: {e}", path=p) from e
    except tomllib.TOMLDecodeError as e:
        m = re.search(r"line (\d+)", str(e))
        raise CalibrationError(f"not valid TOML: {e}", path=p, line=int(m.group(1)) if m else None) from e
    if data.get("format") != FORMAT_ROBOT:
        raise CalibrationError(f"expected format = \"{FORMAT_ROBOT}\", got {data.get('format')!r}", path=p,
                               key="format")
    joints = data.get("joint")
    if not isinstance(joints, list) or len(joints) < 2:
        raise CalibrationError("expected at least two [[joint]] tables", path=p, key="joint")
    cols = {k: [] for k in _JOINT_KEYS}
    for i, j in enumerate(joints):
        for k in j:
            if k not in _JOINT_KEYS:
                raise CalibrationError(f"unknown key in joint {i + 1}." + did_you_mean(k, _JOINT_KEYS), path=p,
                                       line=_line(text, i, k), key=f"joint[{i + 1}].{k}")
        for k in _JOINT_KEYS:
            default = {"beta_deg": 0.0, "theta_offset_deg": 0.0, "limits_deg": [-180.0, 180.0], "mass_kg": 0.0,
                       "com_mm": [0.0, 0.0, 0.0]}.get(k)
            v = j.get(k, default)
            if v is None:
                raise CalibrationError(f"joint {i + 1} needs `{k}`", path=p, key=f"joint[{i + 1}].{k}")
            shape = {"limits_deg": (2,), "com_mm": (3,)}.get(k, ())
            items = v if isinstance(v, list) else [v]
            ok = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in items)
            arr = np.asarray(v, dtype=float) if ok else None
            if arr is None or arr.shape != shape or not np.all(np.isfinite(arr)):
                raise CalibrationError(f"expected {'a number' if not shape else f'{shape[0]} numbers'}, got {v!r}",
                                       path=p, line=_line(text, i, k), key=f"joint[{i + 1}].{k}")
            if k == "limits_deg" and not arr[0] < arr[1]:
                raise CalibrationError(f"limits must be [lower, upper] with lower < upper, got {v}", path=p,
                                       line=_line(text, i, k), key=f"joint[{i + 1}].{k}")
            if k == "mass_kg" and arr < 0:
                raise CalibrationError("mass must be >= 0", path=p, line=_line(text, i, k), key=f"joint[{i + 1}].{k}")
            cols[k].append(arr)
    graw = data.get("gravity_base", [0.0, 0.0, -9.80665])
    ok = isinstance(graw, list) and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in graw)
    g = np.asarray(graw, dtype=float) if ok else np.zeros(0)
    if g.shape != (3,) or not np.all(np.isfinite(g)) or np.linalg.norm(g) == 0:
        raise CalibrationError("gravity_base must be 3 finite numbers [m/s^2], not all zero", path=p,
                               key="gravity_base")
    return Robot(str(data.get("name", p.stem)), *(np.array(cols[k]) for k in _JOINT_KEYS), gravity_base=g, path=p)


def resolve_robot(spec: str | Path) -> Robot:
    """A robot file path, or a built-in name (``tx90``)."""
    p = Path(spec)
    if p.exists() or str(spec).endswith(".toml"):
        return read_robot(p)
    folder = resources.files("rodlab") / "data" / "robots"
    names = {Path(str(f)).stem: Path(str(f)) for f in folder.iterdir() if str(f).endswith(".toml")}
    key = str(spec).strip().lower()                     # built-in names are case-blind: TX90 is tx90
    if key in names:
        return read_robot(names[key])
    raise CalibrationError(f"no such robot file or built-in robot; built-ins: {sorted(names)}."
                           + did_you_mean(str(spec), names), path=spec)
