"""Rod design: the parts of a MultiCal measuring rod and the rules a buildable design obeys.

Geometry (contract, paper Eq. 1 and Fig. 3a): pipe I leaves the flange face along +z of the
flange frame {6}; L1 is measured from the flange face to the bend vertex, L2 from the bend vertex
to the ball centre; gamma is the interior angle between pipe I (pointing back to the flange) and
pipe II, so pipe II points along ``(sin gamma, 0, -cos gamma)`` and gamma = 180 deg is straight.

Part placement (the project's defaults, documented in ``docs/formats.md``):

- ``pipe_holder``: flange adapter, a sleeve over the first ``length_mm`` of pipe I, from the flange face.
- ``ring_1`` / ``ring_2``: sleeves over the last / first ``length_mm`` of pipe I / pipe II, ending
  at the bend's tangent points (where the tubes are bonded to the bend pipe).
- ``bend``: the bend pipe, an arc of ``radius_mm`` between the tangent points
  (tangent length ``radius * tan((180 - gamma)/2)`` from the vertex); absent when gamma = 180.
- ``ball_holder``: a solid stud of ``length_mm`` from the end of pipe II to the ball's pole, held by a
  plug of the same material bonded inside pipe II's bore (diameter = the bore, length = half the bore:
  :attr:`RodDesign.plug_mm`), and reaching into a flat seat of the ball (:attr:`RodDesign.seat_offset_mm`).
- ``ball``: sphere centred on the tool point, with a flat seat where the member that holds it (the stud,
  or pipe II when there is no stud) meets it: the plane where that member's rim touches the sphere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .enums import Part
from .errors import DesignError
from .joint_springs import JointSpring, check_joint_place
from .materials import Material

__all__ = ["TubeSpec", "BendSpec", "SleeveSpec", "BallSpec", "RodDesign", "MIN_BEND_RATIO"]

#: Smallest allowed bend radius as a multiple of the bend pipe's outer diameter.
MIN_BEND_RATIO = 1.5

#: Largest size a design may give [mm]: a measuring rod is well under a metre, so a size beyond 10 m is a typo
#: or another unit (and the closed form overflows on absurd sizes instead of saying so).
MAX_SIZE_MM = 10_000.0


def _check_pos(name: str, value: float, key: str, allow_zero: bool = False) -> None:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise DesignError(f"{name} must be a finite number, got {value!r}", key=key)
    if value < 0 or (value == 0 and not allow_zero):
        raise DesignError(f"{name} must be {'>= 0' if allow_zero else '> 0'}, got {value}", key=key)
    if value > MAX_SIZE_MM:
        raise DesignError(f"{name} must be <= {MAX_SIZE_MM:g} mm (sizes are in millimetres), got {value:g}", key=key)


#: a tube this thin [mm] (outer diameter, wall) is no rod's: the value was given in metres, or mistyped
_METRES_OD_MM, _METRES_WALL_MM = 1.0, 0.05
#: ... in metres where, read as metres, the tube is one a measuring rod could have (outer diameter at most this)
_PLAUSIBLE_OD_MM = 300.0


def _check_not_metres(od: float, wall: float, key: str) -> None:
    """A tube's outer diameter below 1 mm or wall below 0.05 mm: sizes given in metres where, read as metres, they
    make a rod's tube (a designer trial: 0.03 and 0.002 had been read as a tube that sags 9e10 mm, blamed on L2),
    else a size no rod's tube has (a review: a wall of 0.03 on a 40 mm tube is a typo, not 30 mm)."""
    tiny = [(name, v) for name, v, lim in (("outer_diameter_mm", od, _METRES_OD_MM),
                                           ("wall_mm", wall, _METRES_WALL_MM)) if v < lim]
    if not tiny:
        return
    said = ", ".join(f"{name} = {v:g}" for name, v in tiny)
    where = f"{key}.{tiny[0][0]}"
    od_m = 1000 * od if od < _METRES_OD_MM else od
    wall_m = 1000 * wall if wall < _METRES_WALL_MM else wall
    if wall_m < od_m / 2 and od_m <= _PLAUSIBLE_OD_MM:
        given = ", ".join(f"{v:g} m = {1000 * v:g} mm" for _, v in tiny)
        raise DesignError(f"{said}: thinner than any rod's tube; sizes are in millimetres: did you give metres "
                          f"({given})?", key=where)
    raise DesignError(f"{said}: thinner than any rod's tube (an outer diameter of at least {_METRES_OD_MM:g} mm, a "
                      f"wall of at least {_METRES_WALL_MM:g} mm); sizes are in millimetres: check the value",
                      key=where)


@dataclass(frozen=True)
class TubeSpec:
    """A round tube (pipe I, pipe II).

    Attributes: material; outer_diameter_mm [mm]; wall_mm [mm], ``0 < wall < OD/2``.
    """

    material: Material
    outer_diameter_mm: float
    wall_mm: float
    key: str = field(default="tube", compare=False)

    def __post_init__(self) -> None:
        _check_pos("outer_diameter_mm", self.outer_diameter_mm, f"{self.key}.outer_diameter_mm")
        _check_pos("wall_mm", self.wall_mm, f"{self.key}.wall_mm")
        _check_not_metres(self.outer_diameter_mm, self.wall_mm, self.key)
        if self.wall_mm >= self.outer_diameter_mm / 2:
            units = [(u, f) for u, f in (("inches", 25.4), ("centimetres", 10.0))
                     if self.outer_diameter_mm < 10.0                 # thinner than any rod's tube
                     and self.wall_mm < f * self.outer_diameter_mm / 2 <= _PLAUSIBLE_OD_MM / 2]
            if units:                     # a designer trial: an OD of 1.575 (in) had been blamed on the wall
                said = " or ".join(f"{u} ({self.outer_diameter_mm:g} x {f:g} = {f * self.outer_diameter_mm:g} mm)"
                                   for u, f in units)
                raise DesignError(
                    f"outer_diameter_mm = {self.outer_diameter_mm:g} is no more than twice the wall "
                    f"({self.wall_mm:g} mm) and thinner than any rod's tube: in {said}? sizes are in millimetres; "
                    f"else the wall is mistyped", key=f"{self.key}.outer_diameter_mm")
            raise DesignError(
                f"wall {self.wall_mm} mm must be less than the outer radius {self.outer_diameter_mm / 2} mm "
                f"(a tube, not a rod); reduce wall_mm", key=f"{self.key}.wall_mm")

    @property
    def inner_diameter_mm(self) -> float:
        """Bore [mm]."""
        return self.outer_diameter_mm - 2.0 * self.wall_mm


@dataclass(frozen=True)
class BendSpec(TubeSpec):
    """The bend pipe: a tube swept along an arc of ``radius_mm`` [mm] (centreline radius)."""

    radius_mm: float = 0.0

    def __post_init__(self) -> None:
        super().__post_init__()
        _check_pos("radius_mm", self.radius_mm, f"{self.key}.radius_mm")


@dataclass(frozen=True)
class SleeveSpec:
    """A sleeve over a tube (rings, pipe holder) or a solid stud (ball holder).

    Attributes: material; outer_diameter_mm [mm]; length_mm [mm], 0 = part absent.
    """

    material: Material
    outer_diameter_mm: float
    length_mm: float
    key: str = field(default="rings", compare=False)

    def __post_init__(self) -> None:
        _check_pos("outer_diameter_mm", self.outer_diameter_mm, f"{self.key}.outer_diameter_mm")
        _check_pos("length_mm", self.length_mm, f"{self.key}.length_mm", allow_zero=True)

    @property
    def present(self) -> bool:
        """False when ``length_mm == 0``."""
        return self.length_mm > 0


@dataclass(frozen=True)
class BallSpec:
    """The precision ball: material and diameter_mm [mm]."""

    material: Material
    diameter_mm: float

    def __post_init__(self) -> None:
        _check_pos("diameter_mm", self.diameter_mm, "ball.diameter_mm")

    @property
    def radius_mm(self) -> float:
        return self.diameter_mm / 2.0


@dataclass(frozen=True)
class RodDesign:
    """A complete, validated measuring-rod design.

    Attributes
    ----------
    name : rod name (e.g. ``"1#"``)
    L1_mm : flange face to bend vertex along pipe I [mm]
    L2_mm : bend vertex to ball centre along pipe II [mm]
    gamma_deg : interior bend angle in (0, 180] [deg]; 180 = straight
    pipe_I, pipe_II : the two tubes
    bend : the bend pipe (ignored when gamma = 180)
    rings : the two rings (one spec for both)
    pipe_holder : flange adapter sleeve
    ball_holder : solid stud between pipe II and the ball
    ball : the precision ball
    source : the file the design was read from, if any
    tolerances : the file's ``[tolerances]`` table as given ({dotted key: one standard deviation, a number in
        the key's unit or ``"N%"``}); :func:`rodlab.core.tolerances.design_tolerances` adds the defaults
    joints : compliant joints the design declares ({place of :data:`rodlab.core.joint_springs.JOINT_PLACES`:
        :class:`rodlab.core.joint_springs.JointSpring`}, ``rodlab.rod/2``); every compliance method adds them in series
    """

    name: str
    L1_mm: float
    L2_mm: float
    gamma_deg: float
    pipe_I: TubeSpec
    pipe_II: TubeSpec
    bend: BendSpec
    rings: SleeveSpec
    pipe_holder: SleeveSpec
    ball_holder: SleeveSpec
    ball: BallSpec
    source: Path | None = field(default=None, compare=False)
    tolerances: dict = field(default_factory=dict, compare=False)
    joints: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        for place, spring in self.joints.items():
            check_joint_place(place, f"joints.{place}")
            if not isinstance(spring, JointSpring):
                raise DesignError(f"joints.{place}: a JointSpring expected, got {type(spring).__name__}",
                                  key=f"joints.{place}")
        _check_pos("L1_mm", self.L1_mm, "L1_mm")
        _check_pos("L2_mm", self.L2_mm, "L2_mm")
        g = self.gamma_deg
        if isinstance(g, bool) or not isinstance(g, (int, float)) or not math.isfinite(g) or not (0 < g <= 180):
            raise DesignError(f"gamma_deg must lie in (0, 180] (180 = straight rod), got {g!r}", key="gamma_deg")
        problems = self._fit_problems() + self._length_problems()
        if problems:
            raise self._explained(problems)

    def _explained(self, problems: list[DesignError]) -> DesignError:
        """The error for the broken rules ``problems`` (all of them, the first leading): one cause named instead
        when they come from a bend angle in radians or a length in metres."""
        g, first = self.gamma_deg, problems[0]
        if g <= math.pi:            # a bend angle given in radians folds the rod onto itself
            return DesignError(f"gamma_deg = {g:g} degrees folds the rod back onto itself ({first.detail}); gamma_deg "
                               f"is in degrees: did you give radians ({g:g} rad = {math.degrees(g):.1f} deg)?",
                               key="gamma_deg")
        metres = [k for k in ("L1_mm", "L2_mm") if getattr(self, k) < 5.0]      # lengths in metres
        if metres and any(e.key in metres for e in problems):
            said = ", ".join(f"{k} = {getattr(self, k):g}" for k in metres)
            given = ", ".join(f"{getattr(self, k):g} m = {1000 * getattr(self, k):g} mm" for k in metres)
            return DesignError(f"{said}: lengths are in millimetres: did you give metres ({given})? As given, "
                               f"{next(e.detail for e in problems if e.key in metres)}", key=metres[0])
        inches = self._in_inches(problems)
        if inches:
            return inches
        return DesignError(first.detail, key=first.key, also=problems[1:])

    def _in_inches(self, problems: list[DesignError]) -> DesignError | None:
        """The lengths given in inches, where both read as inches make a rod of the checked range (150-1200 and
        250-2000 mm) and a length is too short as given (a designer trial: L1 15.75, L2 23.6 had read "L1 too
        short" alone); None otherwise."""
        L1, L2 = self.L1_mm * 25.4, self.L2_mm * 25.4
        if not (150.0 <= L1 <= 1200.0 and 250.0 <= L2 <= 2000.0) or self.L1_mm >= 100.0:
            return None
        bad = next((e for e in problems if e.key in ("L1_mm", "L2_mm")), None)
        if bad is None:
            return None
        return DesignError(f"L1_mm = {self.L1_mm:g}, L2_mm = {self.L2_mm:g}: lengths are in millimetres: did you give "
                           f"inches ({self.L1_mm:g} in = {L1:.4g} mm, {self.L2_mm:g} in = {L2:.4g} mm)? As given, "
                           f"{bad.detail}", key=bad.key)

    # -- derived geometry ---------------------------------------------------------------
    @property
    def deflection_rad(self) -> float:
        """Turning angle of the bend, ``pi - gamma`` [rad]."""
        return math.pi - math.radians(self.gamma_deg)

    @property
    def has_bend(self) -> bool:
        return self.deflection_rad > 1e-12

    @property
    def tangent_mm(self) -> float:
        """Distance from the bend vertex to either tangent point [mm]."""
        if not self.has_bend:
            return 0.0
        return self.bend.radius_mm * math.tan(self.deflection_rad / 2.0)

    @property
    def tool_mm(self) -> np.ndarray:
        """Nominal ball centre in {6} [mm], shape=(3,) (paper Eq. 1)."""
        gam = math.radians(self.gamma_deg)
        x = self.L2_mm * math.sin(gam)
        z = self.L1_mm - self.L2_mm * math.cos(gam)
        return np.array([0.0 if abs(x) < 1e-12 else x, 0.0, z])

    @property
    def pipe_II_direction(self) -> np.ndarray:
        """Unit vector along pipe II (vertex -> ball) in {6}, shape=(3,)."""
        gam = math.radians(self.gamma_deg)
        return np.array([math.sin(gam), 0.0, -math.cos(gam)])

    def pipe_I_free_mm(self) -> float:
        """Length of pipe I not covered by holder or ring [mm]."""
        return self.L1_mm - self.tangent_mm - self.pipe_holder.length_mm - self.rings.length_mm

    @property
    def seat_diameter_mm(self) -> float:
        """Outer diameter of the member bonded to the ball (ball holder, else pipe II) [mm]."""
        return self.ball_holder.outer_diameter_mm if self.ball_holder.present else self.pipe_II.outer_diameter_mm

    @property
    def seat_offset_mm(self) -> float:
        """Distance from the ball centre to its flat seat, ``sqrt(r^2 - (d/2)^2)`` [mm]."""
        r, a = self.ball.radius_mm, self.seat_diameter_mm / 2.0
        return math.sqrt(max(r * r - a * a, 0.0))

    @property
    def plug_mm(self) -> float:
        """Length of the ball holder's plug inside pipe II's bore [mm] (0 without a ball holder)."""
        return 0.5 * self.pipe_II.inner_diameter_mm if self.ball_holder.present else 0.0

    def pipe_II_length_mm(self) -> float:
        """Length of pipe II from the tangent point to its end (at the ball holder or the ball seat) [mm]."""
        if self.ball_holder.present:
            return self.L2_mm - self.tangent_mm - self.ball.radius_mm - self.ball_holder.length_mm
        return self.L2_mm - self.tangent_mm - self.seat_offset_mm

    def pipe_II_free_mm(self) -> float:
        """Length of pipe II covered by neither ring 2 nor the ball holder's plug [mm]."""
        return self.pipe_II_length_mm() - self.rings.length_mm - self.plug_mm

    # -- rules ---------------------------------------------------------------------------
    def _fit_problems(self) -> list[DesignError]:
        """The part-fit rules this design breaks."""
        out = []
        for ring_tube, label in ((self.pipe_I, "pipe_I"), (self.pipe_II, "pipe_II")):
            if self.rings.present and self.rings.outer_diameter_mm <= ring_tube.outer_diameter_mm:
                out.append(DesignError(
                    f"the rings (OD {self.rings.outer_diameter_mm} mm) do not fit over {label} "
                    f"(OD {ring_tube.outer_diameter_mm} mm): a ring's outer diameter must exceed the tube's; "
                    f"increase rings.outer_diameter_mm", key="rings.outer_diameter_mm"))
        if self.pipe_holder.present and self.pipe_holder.outer_diameter_mm <= self.pipe_I.outer_diameter_mm:
            out.append(DesignError(
                f"the pipe holder (OD {self.pipe_holder.outer_diameter_mm} mm) does not fit over pipe_I "
                f"(OD {self.pipe_I.outer_diameter_mm} mm); increase pipe_holder.outer_diameter_mm",
                key="pipe_holder.outer_diameter_mm"))
        if self.ball_holder.present and self.ball_holder.outer_diameter_mm >= self.ball.diameter_mm:
            out.append(DesignError(
                f"the ball holder (OD {self.ball_holder.outer_diameter_mm} mm) must be narrower than the ball "
                f"({self.ball.diameter_mm} mm); reduce ball_holder.outer_diameter_mm",
                key="ball_holder.outer_diameter_mm"))
        if not self.ball_holder.present and self.pipe_II.outer_diameter_mm >= self.ball.diameter_mm:
            out.append(DesignError(
                f"without a ball holder pipe II (OD {self.pipe_II.outer_diameter_mm} mm) is bonded to the ball and "
                f"must be narrower than it ({self.ball.diameter_mm} mm); add a [ball_holder] or enlarge the ball",
                key="ball.diameter_mm"))
        if self.has_bend:
            for tube, label in ((self.pipe_I, "pipe_I"), (self.pipe_II, "pipe_II")):
                if max(tube.inner_diameter_mm, self.bend.inner_diameter_mm) >= min(
                        tube.outer_diameter_mm, self.bend.outer_diameter_mm):
                    out.append(DesignError(
                        f"the bend pipe (OD {self.bend.outer_diameter_mm}, bore {self.bend.inner_diameter_mm:g} mm) "
                        f"and {label} (OD {tube.outer_diameter_mm}, bore {tube.inner_diameter_mm:g} mm) do not "
                        f"overlap at their joint, so they cannot be bonded; match bend.outer_diameter_mm / wall_mm "
                        f"to the tube", key="bend.outer_diameter_mm"))
            ratio = self.bend.radius_mm / self.bend.outer_diameter_mm
            if ratio < MIN_BEND_RATIO - 1e-9:
                out.append(DesignError(
                    f"bend radius {self.bend.radius_mm} mm is {ratio:.2f} x the bend pipe's diameter "
                    f"{self.bend.outer_diameter_mm} mm; at least {MIN_BEND_RATIO} x is needed "
                    f"(>= {MIN_BEND_RATIO * self.bend.outer_diameter_mm:g} mm) to bend a tube without kinking",
                    key="bend.radius_mm"))
        return out

    def _length_problems(self) -> list[DesignError]:
        """The length rules this design breaks (the parts placed on each pipe must fit on it)."""
        out = []
        free1 = self.pipe_I_free_mm()
        if free1 < -1e-9:
            need = self.L1_mm - free1
            out.append(DesignError(
                f"L1 = {self.L1_mm:g} mm is too short for the parts placed on pipe I: pipe holder "
                f"{self.pipe_holder.length_mm:g} + ring {self.rings.length_mm:.4g} + bend tangent {self.tangent_mm:.1f} "
                f"= {need:.1f} mm; increase L1_mm to at least {need:.1f} or shorten those parts", key="L1_mm"))
        free2 = self.pipe_II_free_mm()
        if free2 < -1e-9:
            need = self.L2_mm - free2
            out.append(DesignError(
                f"L2 = {self.L2_mm:g} mm is too short for the parts placed on pipe II: bend tangent "
                f"{self.tangent_mm:.1f} + ring {self.rings.length_mm:.4g} + ball holder {self.ball_holder.length_mm:g} "
                f"(plug {self.plug_mm:g}) + ball radius {self.ball.radius_mm} = {need:.1f} mm; "
                f"increase L2_mm to at least {need:.1f}",
                key="L2_mm"))
        return out

    def material_of(self, part) -> Material:
        """The material of a part (:class:`~rodlab.core.enums.Part` or its name)."""
        part = Part.parse(part)
        return {Part.PIPE_HOLDER: self.pipe_holder.material, Part.PIPE_I: self.pipe_I.material,
                Part.RING_1: self.rings.material, Part.BEND: self.bend.material, Part.RING_2: self.rings.material,
                Part.PIPE_II: self.pipe_II.material, Part.BALL_HOLDER: self.ball_holder.material,
                Part.BALL: self.ball.material}[part]

    def summary(self) -> dict:
        """Plain-dict description of the design (for ``rodlab info`` and provenance)."""
        def tube(t):
            return {"material": t.material.name, "outer_diameter_mm": t.outer_diameter_mm, "wall_mm": t.wall_mm}

        def sleeve(s):
            return {"material": s.material.name, "outer_diameter_mm": s.outer_diameter_mm, "length_mm": s.length_mm}
        return {
            "name": self.name, "L1_mm": self.L1_mm, "L2_mm": self.L2_mm, "gamma_deg": self.gamma_deg,
            "pipe_I": tube(self.pipe_I), "pipe_II": tube(self.pipe_II),
            "bend": dict(tube(self.bend), radius_mm=self.bend.radius_mm),
            "rings": sleeve(self.rings), "pipe_holder": sleeve(self.pipe_holder),
            "ball_holder": sleeve(self.ball_holder),
            "ball": {"material": self.ball.material.name, "diameter_mm": self.ball.diameter_mm},
        } | ({"joints": {p: vars(j) for p, j in self.joints.items()}} if self.joints else {})
