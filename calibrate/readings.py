"""Raw device readings to ball centres: a campaign's ``s1_mm, s2_mm, s3_mm`` through its device file.

Each point's three readings solve ``A x = sign (s - zero)`` for the ball centre x in {D_j} (:class:`~calibrate.device.
Device`); the sensors' independent noise reaches x as ``A^-1 A^-T`` per unit variance (the campaign's
``noise_shape_D``, which :func:`calibrate.observations.noise_covariance` turns to {W}); with the springs stated
the contact force of each point is the springs' at its readings. A reading outside its sensor's range is
refused (its position, point and line named): the tip had lost the ball or hit its stop.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace

import numpy as np

from .campaign import RAW_COLUMNS, Campaign
from .device import Device
from .errors import CalibrationError

__all__ = ["apply_device", "far_points", "FarPoint", "common_offset", "ALIGNMENT_LIMIT_MM", "unit_slips", "point_unit_slips",
           "limit_breaches", "LIMIT_SLACK_DEG"]

log = logging.getLogger(__name__)

#: how far from the datum point the paper's alignment keeps the ball (Section 3.1); farther, the springs'
#: force and the rod's deflection differ from what a constant contact force assumes
ALIGNMENT_LIMIT_MM = 0.5


def apply_device(camp: Campaign, device: Device) -> Campaign:
    """The campaign with its raw readings converted: ``x_D_mm``, ``noise_shape_D`` and (springs stated)
    ``force_D_N`` per point. Refuses a campaign that has no raw readings and any reading outside its range."""
    if not camp.raw:
        raise CalibrationError(f"the device file ({device.path or device.name}) converts raw sensor readings "
                               f"({', '.join(RAW_COLUMNS)}), but this campaign gives the ball centre in {{D}} "
                               f"(x_mm, y_mm, z_mm); leave --device out", path=camp.path, key="x_mm")
    _check_ranges(camp, device)
    _check_column_units(camp, device)
    x = device.positions(camp.readings_mm)
    shape = np.broadcast_to(device.noise_shape_D(), (camp.n, 3, 3)).copy()
    force = device.force_D(camp.readings_mm) if device.has_springs else None
    log.info("converted %d raw readings with device %s (misalignment %s deg)", camp.n, device.name,
             np.round(device.misalignment_deg(), 3).tolist())
    return replace(camp, x_D_mm=x, noise_shape_D=shape, force_D_N=force)


def _check_ranges(camp: Campaign, device: Device) -> None:
    for k, sensor in enumerate(device.sensors):
        lo, hi = sensor.range_mm
        s = camp.readings_mm[:, k]
        bad = np.nonzero((s < lo) | (s > hi))[0]
        if bad.size:
            i = int(bad[0])
            more = f" ({bad.size - 1} more readings of this sensor are outside too)" if bad.size > 1 else ""
            raise CalibrationError(
                f"position {camp.position[i]} point {camp.point[i]}: sensor {k + 1} reads {s[i]:g} mm, outside "
                f"its range [{lo:g}, {hi:g}] mm (device {device.path or device.name}){more}; "
                + _range_cause(s, bad, lo, hi), path=camp.path, line=int(camp.lines[i]) if camp.lines.size else None,
                key=RAW_COLUMNS[k])


#: a raw column whose median lies this far [mm] from its sensor's zero is no ball aligned near the datum ...
UNIT_SLIP_OFF_MM = 2.0
#: ... and one that, scaled by a unit's factor, lies within this [mm] of the zero was written in that unit
UNIT_SLIP_NEAR_MM = 0.5
_UNITS = ((10.0, "cm", "multiply it by 10"), (25.4, "inches", "multiply it by 25.4"))   # um: out of range first


def _check_column_units(camp: Campaign, device: Device) -> None:
    """Refuse a raw column in another unit: the ball is aligned near the datum, so each sensor reads about its
    ``zero_mm``; a column whose median is far from it and, scaled by 10 or 25.4, near it was written in cm or inches
    (a column in um leaves the sensor's range and is refused before, :func:`_range_cause`; a device trial: s2 in
    cm, 1.25 against a zero of 12.5, had been named as two exchanged columns fitting to 3.4 mm)."""
    for k, sensor in enumerate(device.sensors):
        s = camp.readings_mm[:, k]
        if not np.isfinite(s).any():
            continue
        med = float(np.nanmedian(s))
        if abs(med - sensor.zero_mm) <= UNIT_SLIP_OFF_MM:
            continue
        for factor, unit, fix in _UNITS:
            if abs(factor * med - sensor.zero_mm) <= UNIT_SLIP_NEAR_MM:
                raise CalibrationError(
                    f"sensor {k + 1}'s readings ({RAW_COLUMNS[k]}, median {med:g} mm) lie {abs(med - sensor.zero_mm):.3g}"
                    f" mm from its zero_mm {sensor.zero_mm:g} (device {device.path or device.name}), which a ball "
                    f"aligned near the datum does not give; in {unit} they lie {abs(factor * med - sensor.zero_mm):.2g}"
                    f" mm from it: the column is in {unit}; {fix}", path=camp.path, key=RAW_COLUMNS[k])


def _range_cause(s: np.ndarray, bad: np.ndarray, lo: float, hi: float) -> str:
    """Why a sensor's readings leave its range: most of them, and all within it once divided by 1000, are in um (a
    device trial: 12416.5 'mm' on a 25 mm stroke had been read as a tip that lost the ball); else the tip lost
    the ball or hit its stop."""
    finite = s[np.isfinite(s)]
    if bad.size > 0.5 * max(finite.size, 1) and np.all((finite / 1000 >= lo) & (finite / 1000 <= hi)):
        return ("every reading of this sensor lies within its range once divided by 1000: the readings are in um; "
                "divide the s*_mm columns by 1000")
    return ("the tip lost the ball or hit its stop: align the ball nearer the datum and measure the point again, or "
            "delete the row")


@dataclass(frozen=True)
class FarPoint:
    """A point whose ball centre is ``distance_mm`` [mm] from the datum, at ``line`` of the campaign."""

    position: int
    point: int
    line: int | None
    distance_mm: float

    def __str__(self) -> str:
        at = f" (line {self.line})" if self.line else ""
        return f"position {self.position} point {self.point}{at}: {self.distance_mm:.2f} mm"


def common_offset(x_D_mm: np.ndarray, limit_mm: float = ALIGNMENT_LIMIT_MM) -> np.ndarray | None:
    """The one offset [mm] in {D} most points share (at least 80 % of them farther than ``limit_mm`` from the datum,
    their scatter about their mean under a quarter of it): readings converted with another zero than the device
    aligned with; None otherwise."""
    x = np.asarray(x_D_mm, float)
    if x.ndim != 2 or len(x) < 2:
        return None
    mean = x.mean(axis=0)
    far = int(np.sum(np.linalg.norm(x, axis=1) > limit_mm))
    if far < 0.8 * len(x) or np.linalg.norm(x.std(axis=0)) > 0.25 * np.linalg.norm(mean):
        return None
    return mean


def far_points(camp: Campaign, limit_mm: float = ALIGNMENT_LIMIT_MM) -> list[FarPoint]:
    """The points farther than ``limit_mm`` from the datum point (the paper aligns within about half a mm)."""
    d = np.linalg.norm(camp.x_D_mm, axis=1)
    idx = np.nonzero(d > limit_mm)[0]
    return [FarPoint(int(camp.position[i]), int(camp.point[i]), int(camp.lines[i]) if camp.lines.size else None,
                     float(d[i])) for i in idx]


#: a campaign whose median point lies this far from the datum [mm] was not measured against it (a dial gauge's whole
#: range is 10-25 mm; the paper aligns within 0.5 mm): its readings are in other units
READINGS_UNIT_LIMIT_MM = 25.0


#: ... and this close [mm]: no robot aligns the ball to the datum within 2 um (the paper: 0.5 mm): metres
READINGS_METRES_LIMIT_MM = 0.002
#: instrument points whose median lies within this distance [mm] of the instrument's origin are in metres (a
#: robot's workspace spans hundreds of mm)
POINTS_METRES_LIMIT_MM = 5.0


def unit_slips(camp: Campaign, path) -> list[str]:
    """What in a campaign's numbers says a column is in other units than the contract's, each with its fix: joint
    angles that all lie within +-2 pi (radians where degrees are expected: no campaign turns its joints by less than
    6.3 degrees), readings whose median point lies :data:`READINGS_UNIT_LIMIT_MM` from the datum (um where mm are
    expected) or within :data:`READINGS_METRES_LIMIT_MM` of it (metres); rows in radians among rows in degrees
    (:func:`_radian_rows`). Empty when none."""
    out = _radians(camp.q_deg, path, "campaign") or _radian_rows(camp.q_deg, camp.lines, path, "campaign")
    if camp.x_D_mm is not None and len(camp.x_D_mm):
        d = float(np.median(np.linalg.norm(camp.x_D_mm, axis=1)))
        if d > READINGS_UNIT_LIMIT_MM:
            out.append(f"{path}: the median point lies {d:.1f} mm from the datum point (a MultiCal campaign's lie "
                       f"within about {ALIGNMENT_LIMIT_MM:g} mm, a dial gauge's range is 10-25 mm): the readings look "
                       "like um or another unit; x_mm, y_mm, z_mm are millimetres: divide um by 1000")
        elif d < READINGS_METRES_LIMIT_MM:
            out.append(f"{path}: the median point lies {d * 1e3:.2f} um from the datum point (no robot aligns the ball "
                       f"that closely; a MultiCal campaign's lie within about {ALIGNMENT_LIMIT_MM:g} mm): the readings "
                       "look like metres; x_mm, y_mm, z_mm are millimetres: multiply metres by 1000")
    return out


def point_unit_slips(points, path, sigmas: bool = True) -> list[str]:
    """:func:`unit_slips` of instrument points (``*.validation.csv``): joint angles in radians, positions whose
    median lies within :data:`POINTS_METRES_LIMIT_MM` of the instrument's origin (metres), the rod header in other
    units, and (``sigmas``: unless a stated noise replaces them) sigma columns in um. Empty when none."""
    out = _radians(points.q_deg, path, "points'") or _radian_rows(points.q_deg, None, path, "points'")
    x = np.asarray(points.x_W_mm, float)
    if x.size and float(np.median(np.linalg.norm(x, axis=1))) < POINTS_METRES_LIMIT_MM:
        out.append(f"{path}: the median point lies {np.median(np.linalg.norm(x, axis=1)):.3f} mm from the instrument's "
                   "origin (a robot's workspace spans hundreds of mm): the positions look like metres; x_mm, y_mm, "
                   "z_mm are millimetres: multiply metres by 1000")
    return out + _rod_header_slips(points, path) + (_sigma_slips(points, path) if sigmas else [])


#: a validation rod heavier than this [kg] is a mass in grams (a tracker's target on a short rod: 0.1-2 kg; a trial's
#: 300 g written as 300 gave a 6.3 mm validation error blamed on overfitting)
POINTS_ROD_MASS_LIMIT_KG = 50.0
#: a tool vector shorter than this [mm] (and not zero: points at the flange) is in metres
POINTS_TOOL_METRES_MM = 2.0


#: per-point uncertainties whose median exceeds this [mm] are in um (a tracker's: 0.005-0.1 mm per coordinate; a
#: trial's 12 um written as 12 made the residual test pass at chi-square 0 with a 13 mm noise)
POINTS_SIGMA_LIMIT_MM = 1.0


def _sigma_slips(points, path) -> list[str]:
    """The per-point uncertainty columns in um where mm are expected."""
    s = getattr(points, "sigma_mm", None)
    if s is None or not np.size(s) or float(np.median(s)) <= POINTS_SIGMA_LIMIT_MM:
        return []
    return [f"{path}: the per-point uncertainties' median is {float(np.median(s)):g} mm (an instrument's: 0.005-0.1 "
            "mm per coordinate): sigma_x_mm, sigma_y_mm, sigma_z_mm look like um; they are millimetres: divide um by "
            "1000"]


def _rod_header_slips(points, path) -> list[str]:
    """The points file's rod header in other units: ``rod_mass_kg`` in grams, ``tool_mm`` in metres."""
    out = []
    mass = float(getattr(points, "rod_mass_kg", 0.0))
    if mass > POINTS_ROD_MASS_LIMIT_KG:
        out.append(f"{path}: # rod_mass_kg: {mass:g} (a measuring rod on a robot weighs 0.1-20 kg): it looks like "
                   f"grams; rod_mass_kg is kilograms: write {mass / 1000:g}")
    tool = float(np.linalg.norm(getattr(points, "tool_mm", np.zeros(3))))
    if 0.0 < tool < POINTS_TOOL_METRES_MM:
        out.append(f"{path}: # tool_mm is {tool:.4g} mm long (a tool or target holder reaches tens to hundreds of mm "
                   "from the flange): it looks like metres; tool_mm is millimetres: multiply metres by 1000")
    return out


def _radians(q_deg, path, whose: str) -> list[str]:
    """Joint angles that all lie within +-2 pi and move: radians where degrees are expected."""
    q = np.asarray(q_deg, float)
    if q.size and np.all(np.abs(q) <= 2 * np.pi + 1e-9) and np.ptp(q, axis=0).max() > 0.05:
        return [f"{path}: every joint angle lies within +-2 pi (largest |q| {np.abs(q).max():.3f}): the q columns look "
                f"like radians; the {whose} joint angles are degrees: multiply them by 180/pi"]
    return []


#: a row with at least three joint angles beyond this [rad], one of them beyond 1 rad, moves its joints by tens of
#: degrees if it is in radians; in degrees it is within 6.3 degrees of the zero on every joint and yet clearly off it
#: on three, which a campaign's pose hardly is (a robot's home, all zeros, is not flagged)
_MOVING_RAD = 0.5


def _radian_rows(q_deg, lines, path, whose: str) -> list[str]:
    """Rows in radians among rows in degrees (new-user trial, 2026-11-29: one point, or one clamping position,
    converted to radians passed ``validate``): a row whose joint angles all lie within +-2 pi, with two or more
    beyond :data:`_MOVING_RAD` and one beyond 1, while most rows have one beyond 2 pi."""
    q = np.asarray(q_deg, float)
    if q.ndim != 2 or q.shape[0] < 3:
        return []
    degrees = np.abs(q).max(axis=1) > 2 * np.pi
    if degrees.mean() < 0.5:
        return []
    flagged = np.nonzero(~degrees & ((np.abs(q) > _MOVING_RAD).sum(axis=1) >= 3) & (np.abs(q).max(axis=1) > 1.0))[0]
    if not flagged.size:
        return []
    where = ("line " + ", ".join(str(int(lines[i])) for i in flagged) if lines is not None and len(lines) else
             "data row " + ", ".join(str(i + 1) for i in flagged))
    return [f"{path}: {flagged.size} row(s) ({where}) have every joint angle within +-2 pi while the other rows "
            f"are in degrees: they look like radians; the {whose} joint angles are degrees: multiply those rows' q "
            "columns by 180/pi (a pose truly within 6.3 degrees of the zero on every joint: --units-checked)"]


#: a joint reading this far [deg] beyond the robot file's limit is beyond it (a controller stops at its limit; a
#: reading rounds or overshoots by a hair)
LIMIT_SLACK_DEG = 0.5


def limit_breaches(q_deg, lines, robot, path) -> list[str]:
    """Rows whose joint readings lie beyond the robot file's limits (by more than :data:`LIMIT_SLACK_DEG`): the robot
    file is another robot's, or the controller counts those joints from another zero or the other way. One message
    naming the first rows (file line, or data row without ``lines``) and joints; empty when none."""
    q = np.asarray(q_deg, float)
    if q.ndim != 2 or q.shape[1] != robot.n or not q.size:
        return []
    lo, hi = robot.limits_deg[:, 0] - LIMIT_SLACK_DEG, robot.limits_deg[:, 1] + LIMIT_SLACK_DEG
    out = (q < lo) | (q > hi)
    rows = np.nonzero(out.any(axis=1))[0]
    if not rows.size:
        return []
    shown = []
    for i in rows[:5]:
        k = int(np.nonzero(out[i])[0][0])
        where = f"line {int(lines[i])}" if lines is not None and len(lines) else f"data row {i + 1}"
        shown.append(f"{where} q{k + 1} = {q[i, k]:.2f} of [{robot.limits_deg[k, 0]:g}, {robot.limits_deg[k, 1]:g}]")
    more = f"; and {rows.size - 5} more" if rows.size > 5 else ""
    joints = sorted({int(k) + 1 for k in np.nonzero(out.any(axis=0))[0]})
    return [f"{path}: {rows.size} row(s) have joints beyond the limits of the robot file ({robot.name}): "
            f"{'; '.join(shown)}{more}; the robot file is another robot's, or the controller counts joint(s) "
            f"{', '.join(map(str, joints))} from another zero or the other way: check the robot file and the "
            "controller's export"]
