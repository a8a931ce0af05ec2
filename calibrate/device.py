"""The MultiCal 3-D measuring device (``*.device.json``, ``rodlab.device/1`` or ``/2``): three displacement sensors
whose flat tips push the ball, and the points of its mount that probing the fixture measures.

Sensor k reads ``zero_mm + reading_sign * axis_D . x`` for the ball centre x in {D} (a flat tip on a sphere: only
the displacement along its axis moves the tip; ``reading_sign`` -1, ``rodlab.device/2``, for a sensor whose reading
falls as the ball moves along its axis: a gauge that counts down as its plunger extends, or a channel exported
with the other sign; the sensor still sits on its side of the ball and pushes along ``+axis_D``) and
pushes the ball along ``+axis_D`` with ``force_at_zero_N - rate_N_per_mm * (axis_D . x)``. {D}: x along sensor 1,
y in the plane of sensors 1 and 2, origin at the virtual datum point (the reading ``zero_mm`` of every sensor); the
axes need not be orthogonal. The three readings are three linear equations ``A x = sign (s - zero)`` (rows of A
the axes), solved per point; the sensors' independent noise of one standard deviation sigma becomes
``sigma^2 A^-1 A^-T`` in {D}.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_json, read_json
from rodlab.core.schema import require_schema

from .errors import CalibrationError

__all__ = ["Sensor", "Device", "read_device", "write_device", "device_dict", "ideal_device", "misaligned_device",
           "DEVICE_FORMAT", "DEVICE_FORMAT_SIGNED", "DEVICE_FORMATS", "CONVENTION_TOL", "MAX_CONDITION"]

DEVICE_FORMAT = "rodlab.device/1"
#: /2 adds each sensor's ``reading_sign`` (written only where a sensor reads the other way)
DEVICE_FORMAT_SIGNED = "rodlab.device/2"
DEVICE_FORMATS = (DEVICE_FORMAT, DEVICE_FORMAT_SIGNED)
#: how far sensor 1 may be off x, and sensor 2 off the x-y plane, before the file breaks the convention
CONVENTION_TOL = 1e-6
#: sensors this close to coplanar (condition number of A) cannot locate the ball
MAX_CONDITION = 10.0


@dataclass(frozen=True)
class Sensor:
    """One displacement sensor.

    axis_D : shape=(3,) unit vector in {D}, from the sensor towards the ball (the direction it pushes) [-]
    zero_mm : its reading with the ball centre at the datum point [mm]
    range_mm : (low, high) readings it can give [mm]
    force_at_zero_N : spring force on the ball at the zero reading [N], or None (the fixture's contact force)
    rate_N_per_mm : spring rate [N/mm] (the force falls by it per mm the ball moves along the axis)
    reading_sign : +1 (the reading rises as the ball moves along axis_D) or -1 (it falls: a gauge counting down
    as its plunger extends, a channel exported with the other sign; the sensor still pushes along +axis_D)
    """

    axis_D: np.ndarray
    zero_mm: float
    range_mm: tuple
    force_at_zero_N: float | None = None
    rate_N_per_mm: float = 0.0
    reading_sign: int = 1

    def __post_init__(self):
        a = np.asarray(self.axis_D, dtype=float)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ValueError(f"axis_D must be 3 finite numbers, got {self.axis_D!r}")
        object.__setattr__(self, "axis_D", a)
        lo, hi = (float(v) for v in self.range_mm)
        object.__setattr__(self, "range_mm", (lo, hi))
        if self.reading_sign not in (1, -1):
            raise ValueError(f"reading_sign must be 1 or -1, got {self.reading_sign!r}")


@dataclass
class Device:
    """The device: ``sensors`` (3 :class:`Sensor`), ``features_D_mm`` {name: shape=(3,) point of the mount in
    {D} [mm]} (for fitting the fixture from probes), ``name``, ``path`` it was read from."""

    name: str
    sensors: list
    features_D_mm: dict = field(default_factory=dict)
    path: Path | None = None

    def __post_init__(self):
        if len(self.sensors) != 3:
            raise ValueError(f"a device has 3 sensors, got {len(self.sensors)}")
        self.features_D_mm = {str(k): np.asarray(v, dtype=float) for k, v in self.features_D_mm.items()}

    @property
    def axes(self) -> np.ndarray:
        """A, shape=(3, 3): row k is sensor k's axis in {D}."""
        return np.array([s.axis_D for s in self.sensors])

    @property
    def zero_mm(self) -> np.ndarray:
        return np.array([s.zero_mm for s in self.sensors])

    @property
    def signs(self) -> np.ndarray:
        """shape=(3,): each sensor's reading_sign."""
        return np.array([s.reading_sign for s in self.sensors], float)

    @property
    def has_springs(self) -> bool:
        """Whether every sensor states its spring force (then the contact force follows each reading)."""
        return all(s.force_at_zero_N is not None for s in self.sensors)

    def readings(self, x_D_mm: np.ndarray) -> np.ndarray:
        """Sensor readings [mm], shape=(N, 3), of ball centres x in {D} [mm], shape=(N, 3)."""
        return self.zero_mm + self.signs * (np.asarray(x_D_mm, float) @ self.axes.T)

    def along_axes(self, readings_mm: np.ndarray) -> np.ndarray:
        """shape=(N, 3): how far the ball is along each sensor's axis from the datum point [mm] (A x), from the
        readings [mm], shape=(N, 3)."""
        return self.signs * (np.asarray(readings_mm, float) - self.zero_mm)

    def positions(self, readings_mm: np.ndarray) -> np.ndarray:
        """Ball centres in {D} [mm], shape=(N, 3), from the readings [mm], shape=(N, 3) (A x = sign (s - zero))."""
        return np.linalg.solve(self.axes, self.along_axes(readings_mm).T).T

    def force_D(self, readings_mm: np.ndarray) -> np.ndarray:
        """Contact force on the ball in {D} [N], shape=(N, 3): each spring along its axis at its reading."""
        f0 = np.array([s.force_at_zero_N for s in self.sensors], float)
        rate = np.array([s.rate_N_per_mm for s in self.sensors])
        mag = f0 - rate * self.along_axes(readings_mm)
        return mag @ self.axes

    def noise_shape_D(self) -> np.ndarray:
        """shape=(3, 3): the covariance in {D} of a point from readings of unit, independent noise, A^-1 A^-T."""
        Ainv = np.linalg.inv(self.axes)
        return Ainv @ Ainv.T

    def misalignment_deg(self) -> np.ndarray:
        """shape=(3,): each pair's angle minus 90 deg (sensors 1-2, 1-3, 2-3) [deg]."""
        A = self.axes
        return np.array([np.degrees(np.arccos(np.clip(A[i] @ A[j], -1, 1))) - 90.0
                         for i, j in ((0, 1), (0, 2), (1, 2))])


def ideal_device(name: str = "multical", zero_mm: float = 15.0, range_mm=(0.0, 30.0),
                 force_at_zero_N=(1.10, 1.25, 1.05), rate_N_per_mm: float = 0.04, features: dict | None = None
                 ) -> Device:
    """Orthogonal sensors along x, y, z of {D}, each zeroed at ``zero_mm``, with the paper's contact forces."""
    sensors = [Sensor(np.eye(3)[k], zero_mm, tuple(range_mm), force_at_zero_N[k], rate_N_per_mm) for k in range(3)]
    return Device(name, sensors, DEFAULT_FEATURES_D_MM if features is None else features)


#: the fast-lock's pin and three balls on a typical mount, in {D} [mm] (a fitted frame needs 3 points not in line)
DEFAULT_FEATURES_D_MM = {"pin": [0.0, 0.0, -60.0], "ball_1": [45.0, 0.0, -80.0], "ball_2": [-22.5, 39.0, -80.0],
                         "ball_3": [-22.5, -39.0, -80.0]}


def misaligned_device(base: Device, misalign_deg: float, rng) -> Device:
    """``base`` with sensor 2 turned by ``misalign_deg`` in the x-y plane (random sense) and sensor 3 tilted by
    ``misalign_deg`` in a random direction: the device as built, {D} by the convention (x along sensor 1)."""
    a = np.radians(misalign_deg)
    A = base.axes.copy()
    t2 = a * rng.choice([-1.0, 1.0])
    c, s = np.cos(t2), np.sin(t2)
    A[1] = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ A[1]
    u = np.cross(A[2], rng.normal(size=3))
    u /= np.linalg.norm(u)
    A[2] = np.cos(a) * A[2] + np.sin(a) * np.cross(u, A[2])                 # Rodrigues, u normal to A[2]
    sensors = [Sensor(A[k] / np.linalg.norm(A[k]), s0.zero_mm, s0.range_mm, s0.force_at_zero_N, s0.rate_N_per_mm,
                      s0.reading_sign) for k, s0 in enumerate(base.sensors)]
    return Device(base.name, sensors, dict(base.features_D_mm), base.path)


def device_dict(dev: Device) -> dict:
    """The document of ``dev``: ``rodlab.device/1``, or ``/2`` where a sensor reads the other way."""
    sensors = []
    for s in dev.sensors:
        d = {"axis_D": [round(float(v), 12) for v in s.axis_D], "zero_mm": s.zero_mm, "range_mm": list(s.range_mm)}
        if s.force_at_zero_N is not None:
            d["force_at_zero_N"] = s.force_at_zero_N
            d["rate_N_per_mm"] = s.rate_N_per_mm
        if s.reading_sign != 1:
            d["reading_sign"] = s.reading_sign
        sensors.append(d)
    signed = any(s.reading_sign != 1 for s in dev.sensors)
    out = {"format": DEVICE_FORMAT_SIGNED if signed else DEVICE_FORMAT, "name": dev.name, "sensors": sensors}
    if dev.features_D_mm:
        out["features_D_mm"] = {k: [float(v) for v in p] for k, p in dev.features_D_mm.items()}
    return out


def write_device(dev: Device, path) -> Path:
    return atomic_write_json(path, device_dict(dev))


def read_device(path) -> Device:
    """Read a device file: the schema, then unit axes, the {D} convention, sensors not coplanar, a zero
    inside its range; every error names the file and the key."""
    p = Path(path)
    data, text = read_json(p, CalibrationError)
    if not isinstance(data, dict) or data.get("format") not in DEVICE_FORMATS:
        raise CalibrationError(f"expected a JSON object with \"format\": \"{DEVICE_FORMAT}\" (or "
                               f"\"{DEVICE_FORMAT_SIGNED}\" with a sensor's reading_sign)", path=p, key="format")
    require_schema(data, data["format"], p, text, CalibrationError)
    sensors = [_sensor(p, k, s) for k, s in enumerate(data["sensors"], start=1)]
    _check_convention(p, sensors)
    feats = data.get("features_D_mm", {})
    for name, v in feats.items():
        if not np.all(np.isfinite(v)):
            raise CalibrationError(f"expected 3 finite numbers [mm], got {v}", path=p, key=f"features_D_mm.{name}")
    return Device(str(data.get("name", p.stem)), sensors, feats, p)


def _sensor(p: Path, k: int, s: dict) -> Sensor:
    key = f"sensors[{k}]"
    a = np.asarray(s["axis_D"], float)
    with np.errstate(over="ignore", invalid="ignore"):
        n = float(np.linalg.norm(a))
    if not np.all(np.isfinite(a)) or abs(n - 1.0) > 1e-3:
        raise CalibrationError(f"sensor {k}'s axis must be a unit vector, got {s['axis_D']} (length {n:.6g}); "
                               f"divide it by its length", path=p, key=f"{key}.axis_D")
    lo, hi = s["range_mm"]
    if not lo < hi:
        raise CalibrationError(f"expected [low, high] with low < high [mm], got {s['range_mm']}", path=p,
                               key=f"{key}.range_mm")
    if not lo <= s["zero_mm"] <= hi:
        raise CalibrationError(f"the zero reading {s['zero_mm']:g} mm is outside the range [{lo:g}, {hi:g}] mm",
                               path=p, key=f"{key}.zero_mm")
    for k2 in ("zero_mm", "force_at_zero_N", "rate_N_per_mm"):
        if k2 in s and not np.isfinite(s[k2]):
            raise CalibrationError(f"expected a finite number, got {s[k2]!r}", path=p, key=f"{key}.{k2}")
    if not np.all(np.isfinite(s["range_mm"])):
        raise CalibrationError(f"expected 2 finite numbers [mm], got {s['range_mm']}", path=p, key=f"{key}.range_mm")
    if "rate_N_per_mm" in s and "force_at_zero_N" not in s:
        raise CalibrationError("a spring rate needs the spring's force at the zero reading (force_at_zero_N)",
                               path=p, key=f"{key}.force_at_zero_N")
    _check_spring(p, key, s, float(lo), float(hi))
    return Sensor(a / n, float(s["zero_mm"]), (float(lo), float(hi)), s.get("force_at_zero_N"),
                  float(s.get("rate_N_per_mm", 0.0)), int(s.get("reading_sign", 1)))


def _check_spring(p: Path, key: str, s: dict, lo: float, hi: float) -> None:
    """Refuse a spring that would stop pushing the ball within :data:`SPRING_SPAN_MM` of the zero reading, where a
    ball aligned near the datum is read (a device trial's rate in N/m written as N/mm, 40 for 0.04, pulled the
    ball with -11 N and was blamed on the rod)."""
    f0, rate = s.get("force_at_zero_N"), float(s.get("rate_N_per_mm", 0.0))
    if f0 is None or not rate:
        return
    zero = float(s["zero_mm"])
    span = [max(lo, zero - SPRING_SPAN_MM), min(hi, zero + SPRING_SPAN_MM)]
    ends = [float(f0) - rate * float(s.get("reading_sign", 1) or 1) * (r - zero) for r in span]
    if min(ends) > 0:
        return
    per_m = f"; in N/m? ({rate:g} N/m = {rate / 1000:g} N/mm)" if float(f0) > abs(rate / 1000) * SPRING_SPAN_MM else ""
    raise CalibrationError(f"a spring of {f0:g} N at the zero reading and {rate:g} N/mm pushes with {min(ends):.3g} N "
                           f"{SPRING_SPAN_MM:g} mm from it: it would stop touching a ball aligned near the datum"
                           f"{per_m}; give the rate in N/mm (the force falls by it per mm the ball moves along the "
                           "axis)", path=p, key=f"{key}.rate_N_per_mm")


#: a sensor's spring must push the ball over this span [mm] either side of its zero reading
SPRING_SPAN_MM = 1.0


#: how a sensor that reads the other way is declared (a device trial: it could only be turned round or rewritten)
REVERSED_FIX = ("keep axis_D as designed (from the sensor towards the ball: the direction it pushes) and declare the "
                "sensor's reading_sign -1 (format rodlab.device/2), or write its readings as 2 x zero_mm - reading")


def _check_convention(p: Path, sensors: list) -> None:
    A = np.array([s.axis_D for s in sensors])
    if np.linalg.norm(A[0] - [1.0, 0.0, 0.0]) > CONVENTION_TOL:
        raise CalibrationError(f"{{D}} has x along sensor 1: its axis must be [1, 0, 0], got {A[0].tolist()}; "
                               f"express the axes in that frame", path=p, key="sensors[1].axis_D")
    if abs(A[1, 2]) > CONVENTION_TOL:
        raise CalibrationError(f"{{D}} has y in the plane of sensors 1 and 2: sensor 2's z must be 0, got "
                               f"{A[1, 2]:g}; express the axes in that frame", path=p, key="sensors[2].axis_D")
    if A[1, 1] <= 0:                      # review: a reversed sensor 2 had been blamed on sensor 3
        raise CalibrationError(f"{{D}} has y on sensor 2's side of the x axis: sensor 2's y must be > 0, got "
                               f"{A[1, 1]:g}. A sensor that reads the other way (its reading falling as the ball "
                               f"moves along its axis) is not a device axis: {REVERSED_FIX}", path=p,
                               key="sensors[2].axis_D")
    if np.linalg.cond(A) > MAX_CONDITION:
        raise CalibrationError(f"the three sensor axes are (nearly) coplanar (condition {np.linalg.cond(A):.3g}; expected "
                               f"<= {MAX_CONDITION:g}): each sensor's axis_D is the direction its reading grows in "
                               "{D}; give the three as measured", path=p, key="sensors")
    if np.linalg.det(A) <= 0:             # a device trial: a reversed sensor 3 written as -z had no fix
        raise CalibrationError(f"the three sensor axes are left-handed (det {np.linalg.det(A):.3g}; expected > 0): "
                               "sensor 3 must point to the side of +z that sensors 1 and 2 make right-handed. A sensor "
                               "that reads the other way (its reading falling as the ball moves along its axis) is "
                               f"not a device axis: {REVERSED_FIX}", path=p, key="sensors[3].axis_D")
