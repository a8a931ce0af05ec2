"""Any serial chain to the calibrator's model: joint axes as lines at the zero configuration -> DH rows.

Every robot description (URDF, DH, modified DH) is first reduced to a :class:`ZeroChain`: the joint axes as
lines in the description's base frame at q = 0, the tip frame (flange / ``tool0``) and the links' masses. The
rows of the calibrator's model ``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)`` then follow
from the common normals of consecutive axes (Denavit-Hartenberg; ``beta = 0`` except on Hayati's rows):

- ``z_{i-1}`` runs along joint i's axis *in the description's positive direction*, so the model's joint
  angle is the description's (``theta_i = q_i + theta_offset_i``) and no sign table is needed;
- non-parallel consecutive axes: ``x_i`` along their common normal (``z_{i-1} x z_i`` where they
  intersect), ``d_i`` and ``a_i`` the normal's foot and length;
- parallel or nearly parallel consecutive axes (within ``NEAR_PARALLEL_DEG``): the common normal is not unique
  or lies far away (two axes 2e-4 deg apart in a URDF give a normal kilometres off), so the row is Hayati's:
  ``x_i`` from ``o_{i-1}`` (``d_i = 0``) to where joint i + 1's axis crosses the plane normal to ``z_{i-1}``,
  ``alpha_i`` and ``beta_i`` the small tilt between the axes; the calibrator identifies ``beta_i`` there
  instead of ``d_i``;
- the last row ends on the tip frame (:func:`end_row`): for a flange on the last axis, tilted or not, ``{n}``
  is the tip frame exactly; a tip off the axis keeps a turn about z in ``n_T_tip``;
- ``{0}``: ``z_0`` on joint 1's axis through the foot of the base origin, ``x_0`` the base x projected.

The conversion is exact: the model's forward kinematics equals the description's for every configuration
(tested to 1e-6 mm), with ``base_T_0`` (pose of {0} in the base frame) and ``n_T_tip`` (tip in {n}).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["ZeroChain", "DhRows", "dh_rows", "end_row", "row_matrix", "chain_matrices", "NEAR_PARALLEL_DEG"]

#: two consecutive joint axes closer than this [deg] get a Hayati row (d = 0, alpha and beta the tilt)
NEAR_PARALLEL_DEG = 1.0
_NEAR_PARALLEL = math.sin(math.radians(NEAR_PARALLEL_DEG))
_END_TILT_COS = math.cos(math.radians(45.0))   # a tip z within 45 deg of the last axis: a flange on it
_ON_TIP_AXIS = 1e-6  # mm: a tip origin this close to the last axis lies on it
_ON_AXIS = 1e-9      # mm: a common normal shorter than this is an intersection


@dataclass(frozen=True)
class ZeroChain:
    """A serial chain of revolute joints at q = 0, in the description's base frame.

    Attributes (n = number of joints)
    ---------------------------------
    name : robot name; source : where the description came from (file, data sheet)
    axis_point_mm : shape=(n, 3) [mm], a point on joint i's axis; axis_dir : shape=(n, 3), unit direction
        (positive rotation by the right hand)
    tip_T : shape=(4, 4) [mm], the tip frame (flange / tool0) at q = 0
    limits_deg : shape=(n, 2); link_mass_kg : shape=(n,), the mass moved by joint i and not by joint i + 1;
    link_com_mm : shape=(n, 3) [mm], its centre of mass at q = 0; gravity : shape=(3,) [m/s^2]
    """

    name: str
    axis_point_mm: np.ndarray
    axis_dir: np.ndarray
    tip_T: np.ndarray
    limits_deg: np.ndarray
    link_mass_kg: np.ndarray
    link_com_mm: np.ndarray
    gravity: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.80665]))
    source: str = ""

    def __post_init__(self) -> None:
        n = int(np.shape(self.axis_point_mm)[0])
        shapes = {"axis_point_mm": (n, 3), "axis_dir": (n, 3), "tip_T": (4, 4), "limits_deg": (n, 2),
                  "link_mass_kg": (n,), "link_com_mm": (n, 3), "gravity": (3,)}
        for k, shape in shapes.items():
            if np.shape(getattr(self, k)) != shape:
                raise ValueError(f"ZeroChain.{k} must have shape {shape}, got {np.shape(getattr(self, k))}")
        norms = np.linalg.norm(self.axis_dir, axis=1)
        if np.any(np.abs(norms - 1.0) > 1e-9):
            raise ValueError(f"ZeroChain.axis_dir must be unit vectors, got norms {norms}")
        if n < 2:
            raise ValueError(f"a serial chain needs at least 2 revolute joints, got {n}")


@dataclass(frozen=True)
class DhRows:
    """The model's nominal rows and the frames that tie it to its description.

    theta_offset_deg, d_mm, a_mm, alpha_deg, beta_deg : shape=(n,); base_T_0 : {0} in the base frame [mm];
    n_T_tip : the tip frame in {n} [mm]; frames_T : shape=(n + 1, 4, 4), {0}..{n} in the base frame at q = 0;
    com_mm : shape=(n, 3), link i's centre of mass in {i}
    """

    theta_offset_deg: np.ndarray
    d_mm: np.ndarray
    a_mm: np.ndarray
    alpha_deg: np.ndarray
    beta_deg: np.ndarray
    base_T_0: np.ndarray
    n_T_tip: np.ndarray
    frames_T: np.ndarray
    com_mm: np.ndarray


def row_matrix(theta, d, a, alpha, beta=0.0) -> np.ndarray:
    """``Rz(theta) Tz(d) Tx(a) Rx(alpha) Ry(beta)`` [rad, mm], one 4x4."""
    ct, st, ca, sa, cb, sb = (math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha),
                              math.cos(beta), math.sin(beta))
    RzRx = np.array([[ct, -st * ca, st * sa], [st, ct * ca, -ct * sa], [0.0, sa, ca]])
    T = np.eye(4)
    T[:3, :3] = RzRx @ np.array([[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]])
    T[:3, 3] = (a * ct, a * st, d)
    return T


def chain_matrices(theta_deg, d, a, alpha_deg, beta_deg) -> np.ndarray:
    """Frames {0}..{n} of one configuration's rows (theta includes q), shape=(n + 1, 4, 4)."""
    out = [np.eye(4)]
    for row in zip(np.deg2rad(theta_deg), d, a, np.deg2rad(alpha_deg), np.deg2rad(beta_deg)):
        out.append(out[-1] @ row_matrix(*row))
    return np.array(out)


def _frame(origin, x, z) -> np.ndarray:
    T = np.eye(4)
    T[:3, 0], T[:3, 2] = x, z
    T[:3, 1] = np.cross(z, x)
    T[:3, 3] = origin
    return T


def _unit(v) -> np.ndarray:
    return np.asarray(v, float) / np.linalg.norm(v)


def _perpendicular(hint, z, fallback) -> np.ndarray:
    """``hint`` with its z component removed (``fallback`` when hint lies along z)."""
    for v in (hint, fallback, np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])):
        w = np.asarray(v, float) - np.dot(v, z) * z
        if np.linalg.norm(w) > 1e-6:
            return _unit(w)
    raise AssertionError("unreachable: two orthogonal fallbacks")


def _common_normal(o, z, p, u):
    """Feet ``(c1, c2)`` of the common normal from line (o, z) to line (p, u), which are not nearly parallel."""
    r = p - o
    zu = np.dot(z, u)
    den = 1.0 - zu * zu
    s = (np.dot(r, z) - zu * np.dot(r, u)) / den
    t = (zu * np.dot(r, z) - np.dot(r, u)) / den
    return o + s * z, p + t * u


def _normal_row(frame, p, u):
    """The DH row (theta, d, a, alpha, beta = 0) from ``frame`` to the line (p, u), and the next frame."""
    o, x_prev, z = frame[:3, 3], frame[:3, 0], frame[:3, 2]
    c1, c2 = _common_normal(o, z, p, u)
    a = float(np.linalg.norm(c2 - c1))
    if a > _ON_AXIS:
        x = (c2 - c1) / a
    else:                                              # intersecting axes: the sign nearest the previous x
        x = _unit(np.cross(z, u))
        x = -x if np.dot(x, x_prev) < -1e-9 else x
    row = (_signed_angle(x_prev, x, z), float(np.dot(c1 - o, z)), a, _signed_angle(z, u, x), 0.0)
    return row, _frame(c1 + a * x, x, u)


def _hayati_row(frame, p, u, hint, last: bool):
    """Hayati's row to a (nearly) parallel line (p, u): ``d = 0`` (the last row: the foot of the tip), ``x``
    towards where the line crosses the plane normal to ``z`` there, ``Rx(alpha) Ry(beta)`` turning ``z`` onto ``u``."""
    o, x_prev, z = frame[:3, 3], frame[:3, 0], frame[:3, 2]
    c1 = o + np.dot(p - o, z) * z if last else o       # the flange at the end
    c2 = p - np.dot(p - c1, z) / np.dot(u, z) * u      # the line through the plane at c1 normal to z
    a = float(np.linalg.norm(c2 - c1))
    x = (c2 - c1) / a if a > _ON_AXIS else _perpendicular(hint, z, x_prev)
    y = np.cross(z, x)
    alpha = math.atan2(0.0 - float(np.dot(u, y)), float(np.dot(u, z)))   # 0.0 - : +pi, not -pi
    beta = math.asin(float(np.clip(np.dot(u, x), -1.0, 1.0)))
    row = (_signed_angle(x_prev, x, z), float(np.dot(c1 - o, z)), a, alpha, beta)
    nxt = np.eye(4)
    nxt[:3, :3] = np.c_[x, y, z] @ row_matrix(0.0, 0.0, 0.0, alpha, beta)[:3, :3]
    nxt[:3, 3] = c2
    return row, nxt


def _signed_angle(v1, v2, axis) -> float:
    return math.atan2(float(np.dot(np.cross(v1, v2), axis)), float(np.dot(v1, v2)))


def _first_frame(chain: ZeroChain) -> np.ndarray:
    z0 = _unit(chain.axis_dir[0])
    p = chain.axis_point_mm[0]
    origin = p - np.dot(p, z0) * z0                    # the foot of the base origin on axis 1
    return _frame(origin, _perpendicular([1.0, 0.0, 0.0], z0, [0.0, 1.0, 0.0]), z0)


def _next_row(frame, p, u, hint, last: bool):
    """The row from ``frame`` to the line (p, u) (the next axis, or the tip's z for the last row)."""
    if np.linalg.norm(np.cross(frame[:3, 2], u)) < _NEAR_PARALLEL:
        return _hayati_row(frame, p, u, hint, last)
    return _normal_row(frame, p, u)


def end_row(prev_T: np.ndarray, tip_T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The last row ``(theta, d, a, alpha, beta)`` [rad, mm] from frame {n-1} to a tip frame (both 4x4, one
    frame at q = 0), and ``{n}`` itself. A tip whose z is within 45 deg of the last axis: ``{n}`` *is* the tip
    frame when the tip's origin lies on the axis (``Rz(theta) Rx(alpha) Ry(beta)`` its rotation exactly), and
    otherwise has the tip's origin and z (Hayati's row; what is left is a turn about z, in ``n_T_tip``)."""
    o, z = prev_T[:3, 3], prev_T[:3, 2]
    p, u = tip_T[:3, 3], _unit(tip_T[:3, 2])
    if abs(float(np.dot(u, z))) < _END_TILT_COS:
        row, frame = _normal_row(prev_T, p, u)
    elif np.linalg.norm((p - o) - np.dot(p - o, z) * z) < _ON_TIP_AXIS:
        theta, alpha, beta = _zxy_angles(prev_T[:3, :3].T @ tip_T[:3, :3])
        row = (theta, float(np.dot(p - o, z)), 0.0, alpha, beta)
        frame = prev_T @ row_matrix(*row)
    else:
        row, frame = _hayati_row(prev_T, p, u, tip_T[:3, 0], True)
    return np.asarray(row, float), frame


def _zxy_angles(R: np.ndarray) -> tuple[float, float, float]:
    """``(theta, alpha, beta)`` with ``R = Rz(theta) Rx(alpha) Ry(beta)``, of the two solutions the one with
    ``|beta| <= 90 deg`` (a flange turned over is ``alpha = 180``, as the common normal gives it), angles in
    (-180, 180] deg."""
    theta, alpha = math.atan2(-R[0, 1], R[1, 1]), math.asin(float(np.clip(R[2, 1], -1.0, 1.0)))
    beta = math.atan2(-R[2, 0], R[2, 2])
    if abs(beta) > math.pi / 2:                       # Rz(t + pi) Rx(pi - a) Ry(b + pi) is the same rotation
        theta, alpha, beta = theta + math.pi, math.pi - alpha, beta + math.pi

    def wrap(x: float) -> float:
        y = math.remainder(x, 2 * math.pi)
        return math.pi if y <= -math.pi + 1e-12 else y
    return wrap(theta), wrap(alpha), wrap(beta)


def dh_rows(chain: ZeroChain) -> DhRows:
    """The nominal rows of the calibrator's model for ``chain`` (exact; see the module docstring)."""
    n = chain.axis_dir.shape[0]
    frames = [_first_frame(chain)]
    rows = np.zeros((n, 5))
    for i in range(n - 1):
        rows[i], frame = _next_row(frames[-1], chain.axis_point_mm[i + 1], _unit(chain.axis_dir[i + 1]),
                                   frames[-1][:3, 0], False)
        frames.append(frame)
    rows[-1], frame = end_row(frames[-1], chain.tip_T)
    frames.append(frame)
    return _assemble(chain, rows, frames)


def _assemble(chain: ZeroChain, rows: np.ndarray, frames: list) -> DhRows:
    F = np.array(frames)
    base_T_0 = F[0]
    # the frames as the rows rebuild them (exact up to round-off; the rows define the model)
    rebuilt = base_T_0 @ chain_matrices(np.rad2deg(rows[:, 0]), rows[:, 1], rows[:, 2], np.rad2deg(rows[:, 3]),
                                         np.rad2deg(rows[:, 4]))
    n_T_tip = np.linalg.inv(rebuilt[-1]) @ chain.tip_T
    com = np.einsum("nij,nj->ni", np.linalg.inv(rebuilt[1:]), np.c_[chain.link_com_mm, np.ones(len(rows))])[:, :3]
    return DhRows(np.rad2deg(rows[:, 0]), rows[:, 1].copy(), rows[:, 2].copy(), np.rad2deg(rows[:, 3]),
                  np.rad2deg(rows[:, 4]), base_T_0, n_T_tip, rebuilt, com)
