"""Compliant joints a design declares (``rodlab.rod/2`` ``[joints.PLACE]``): rotational springs in series with the
rod's members, added to every compliance method's C_F and C_g.

A design models its bonds as rigid. Their places are the flange clamp, ring 1 and pipe II (``pipe_II`` stands for
ring 2 and the ball holder, which tip loads cannot tell apart: contract effects.md). A rod whose
bond was measured compliant (``rodlab update --free joints.ring_1.s_bend_rad_per_Nm``), or a designer who wants to
see what a softer bond does, declares it::

    [joints.ring_1]
    s_bend_rad_per_Nm = 2e-6       # bending compliance [rad/(N m)], about both axes across the member
    s_torsion_rad_per_Nm = 0.0     # torsion compliance about the member axis [rad/(N m)], optional

A spring at point p on a member along t rotates what lies beyond it by theta = S M, with M the moment about p of
the load beyond it and S = s_bend (1 - t t^T) + s_torsion t t^T; the ball centre (origin of {T}) moves by
theta x r, r from the spring to the ball. A tip force gives :func:`spring_matrices`; the rod's own weight beyond the
spring gives the C_g increment of :func:`declared_joint_compliance`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .errors import DesignError, did_you_mean
from .units import G0

__all__ = ["JOINT_PLACES", "JOINT_KEYS", "JointSpring", "JointPlace", "joint_place", "design_joint_places",
           "spring_matrices", "declared_joint_compliance", "check_joint_place"]

#: places where a design's rigid bonds may be compliant (the rig effect ``joint_compliance``'s locations)
JOINT_PLACES = ("flange_clamp", "ring_1", "pipe_II")
#: the keys of a ``[joints.PLACE]`` table [rad/(N m)]
JOINT_KEYS = ("s_bend_rad_per_Nm", "s_torsion_rad_per_Nm")


def check_joint_place(place: str, key: str) -> None:
    """:class:`DesignError` naming ``key`` unless ``place`` is one of :data:`JOINT_PLACES`."""
    if place not in JOINT_PLACES:
        raise DesignError(f"unknown joint place {place!r}; places: {list(JOINT_PLACES)}." +
                          did_you_mean(place, JOINT_PLACES), key=key)


@dataclass(frozen=True)
class JointSpring:
    """A declared compliant joint.

    s_bend_rad_per_Nm : bending compliance about both axes across the member [rad/(N m)], >= 0
    s_torsion_rad_per_Nm : torsion compliance about the member axis [rad/(N m)], >= 0
    """

    s_bend_rad_per_Nm: float = 0.0
    s_torsion_rad_per_Nm: float = 0.0

    def __post_init__(self) -> None:
        for name in JOINT_KEYS:
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v < 0 or v > 1e-2:
                raise DesignError(f"{name} must be a number in [0, 1e-2] rad/(N m) (a sound bond is ~1e-7), got "
                                  f"{v!r}", key=name)
            object.__setattr__(self, name, float(v))


@dataclass(frozen=True)
class JointPlace:
    """Where a joint sits: point_T_mm : the spring's point in {T} [mm], shape=(3,); axis_T : the member's unit
    axis there, shape=(3,); s_mm : arc length from the flange face along the centreline [mm]."""

    point_T_mm: np.ndarray
    axis_T: np.ndarray
    s_mm: float

    def __post_init__(self) -> None:
        for name in ("point_T_mm", "axis_T"):
            v = np.asarray(getattr(self, name), float)
            if v.shape != (3,) or not np.all(np.isfinite(v)):
                raise ValueError(f"JointPlace.{name}: a finite vector of shape (3,) expected, got {v!r}")
            object.__setattr__(self, name, v)


def design_joint_places(design) -> dict[str, JointPlace]:
    """The places of :data:`JOINT_PLACES` the design has, from its layout: the flange clamp at the flange face,
    ring 1 and pipe II at their middles."""
    from .layout import layout  # cycle: layout imports design, which imports this module
    segs = layout(design)
    tool = design.tool_mm

    def mid(seg) -> JointPlace:
        return JointPlace(seg.point([seg.length_mm / 2])[0] - tool, seg.tangent([seg.length_mm / 2])[0],
                          seg.s0_mm + seg.length_mm / 2)
    out = {"flange_clamp": JointPlace(segs[0].start_F - tool, segs[0].direction, 0.0)}
    ring1 = [s for s in segs if any(str(layer.part) == "ring_1" for layer in s.layers)]
    if ring1:
        out["ring_1"] = mid(ring1[0])
    pipe2 = [s for s in segs if any(str(layer.part) == "pipe_II" for layer in s.layers)]
    if pipe2:
        out["pipe_II"] = mid(pipe2[len(pipe2) // 2])
    return out


def joint_place(design, place: str) -> JointPlace:
    """One place of :func:`design_joint_places`; :class:`DesignError` when the design has no such part."""
    check_joint_place(place, f"joints.{place}")
    places = design_joint_places(design)
    if place not in places:
        raise DesignError(f"design {design.name!r} has no {place} (its part is absent)", key=f"joints.{place}")
    return places[place]


def _axes(axis_T) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.asarray(axis_T, float) / np.linalg.norm(axis_T)
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    b1 = np.cross(t, helper)
    b1 /= np.linalg.norm(b1)
    return b1, np.cross(t, b1), t


def spring_matrices(point_T, axis_T) -> tuple[np.ndarray, np.ndarray]:
    """C_F increments [mm/N] per unit bending and torsion compliance [rad/(N mm)] of a rotational spring at
    ``point_T`` (in {T}) on a member along ``axis_T``.

    A tip force F makes a moment (0 - point) x F about the spring; each compliant rotation axis e with
    compliance s adds ``s (e x r)(e x r)^T`` with r from the spring to the ball centre (origin of {T}): the two
    axes across the member bend, the member axis twists.
    """
    r = -np.asarray(point_T, float)
    b1, b2, t = _axes(axis_T)
    Cb = sum(np.outer(np.cross(e, r), np.cross(e, r)) for e in (b1, b2))
    Ct = np.outer(np.cross(t, r), np.cross(t, r))
    return Cb, Ct


def _gravity_matrices(place: JointPlace, mass_kg: float, com_T_mm) -> tuple[np.ndarray, np.ndarray]:
    """C_g increments [mm per g0] per unit bending and torsion compliance [rad/(N mm)]: the weight
    ``mass_kg * G0`` at ``com_T_mm`` beyond the spring turns it by s (e . (a x W)) about each axis e, a from the
    spring to the centre of mass, and the ball moves by (e x r) times that."""
    r = -place.point_T_mm
    a = np.asarray(com_T_mm, float) - place.point_T_mm
    b1, b2, t = _axes(place.axis_T)
    w = mass_kg * G0
    Gb = sum(np.outer(np.cross(e, r), np.cross(e, a)) for e in (b1, b2)) * w
    Gt = np.outer(np.cross(t, r), np.cross(t, a)) * w
    return Gb, Gt


def declared_joint_compliance(design) -> tuple[np.ndarray, np.ndarray]:
    """(C_F [mm/N], C_g [mm per g0]) the design's declared joints add, shape=(3, 3) each; zeros without any."""
    CF, Cg = np.zeros((3, 3)), np.zeros((3, 3))
    joints = getattr(design, "joints", None) or {}
    if not any(j.s_bend_rad_per_Nm or j.s_torsion_rad_per_Nm for j in joints.values()):
        return CF, Cg
    from .massprops import distal_mass_properties  # cycle: massprops imports design, which imports this module
    for place, spring in joints.items():
        where = joint_place(design, place)
        sb, st = spring.s_bend_rad_per_Nm * 1e-3, spring.s_torsion_rad_per_Nm * 1e-3   # rad/(N mm)
        Cb, Ct = spring_matrices(where.point_T_mm, where.axis_T)
        beyond = distal_mass_properties(design, where.s_mm)
        Gb, Gt = _gravity_matrices(where, beyond.mass_kg, beyond.com_T_mm)
        CF += sb * Cb + st * Ct
        Cg += sb * Gb + st * Gt
    return 0.5 * (CF + CF.T), Cg
