"""Where the rod models hold: the design range they were checked on, and rods no model here describes.

Two kinds of rule about the whole design (single-part rules, such as a ring that does not fit over its tube,
live in :class:`~rodlab.core.design.RodDesign`):

- **refused** (:class:`~rodlab.core.errors.DesignError`, raised by :func:`check_design`): a rod that would hang
  rather than reach, its self-weight sag above ``SAG_LIMIT`` of its reach: every compliance in rodlab
  (closed form, frame, solid FEA, Eqs. 15-18) is linear, valid for deflections small against the length.
  (Parts that cannot be assembled, such as a bend too tight for L1, are :class:`~rodlab.core.design.RodDesign`'s
  own rules; with them pipe II cannot run through the flange.)

- **warned** (:func:`range_warnings`): a key outside ``VERIFIED_RANGE`` (the designs on which the frame
  model was checked against solid FEA: ``fea/data/solid_reference.json`` and
  ``docs/benchmarks/frame_range.md``), the ball behind the flange plane (pipe II reaching back beside the
  robot's wrist: a clearance to check on the robot), or a second-order error of the linear models, about
  ``delta^2 / reach`` for a self-weight sag ``delta``, above ``LINEAR_WARN_MM`` (the order of a laser
  tracker's noise).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .calc import calc_compliance
from .design import RodDesign
from .errors import DesignError

__all__ = ["laminate_bend_warning", "VERIFIED_RANGE", "SAG_LIMIT", "LINEAR_WARN_MM", "RangeWarning", "range_warnings",
           "check_design", "linear_model_error_mm"]

#: key -> (low, high, unit): where the frame model was checked against solid FEA (the six paper rods, the
#: calibration / probe / held-out sets, and the corners in docs/benchmarks/frame_range.md: within 1.4 % of each
#: matrix's largest entry on the built-in rods' thick tubes, 0.8 % on the thin-walled rods of before #45; the
#: short rods' and the sharpest bend's small entries within 10 %)
VERIFIED_RANGE: dict[str, tuple[float, float, str]] = {
    "L1_mm": (150.0, 1200.0, "mm"),
    "L2_mm": (250.0, 2000.0, "mm"),
    "gamma_deg": (60.0, 180.0, "deg"),
}
#: self-weight sag, as a fraction of the reach, above which a design is refused
SAG_LIMIT = 0.25
#: ... and above which it is warned about [mm] (a laser tracker's noise is a few um to 10 um)
LINEAR_WARN_MM = 0.01


@dataclass(frozen=True)
class RangeWarning:
    """A design key outside the range the models were checked on.

    Attributes
    ----------
    key : the design key (``L2_mm``); value : its value in the design
    low, high : the checked range of the key (same unit); unit : ``mm`` or ``deg``
    reason : what is not verified or not reliable there
    """

    key: str
    value: float
    low: float
    high: float
    unit: str
    reason: str
    about_range: bool = True

    @property
    def outside(self) -> bool:
        return not self.low <= self.value <= self.high

    def describe(self) -> str:
        """``key `K` = v unit lies outside lo-hi unit: reason``; a warning not about the checked range (the rod's
        sag, ``about_range`` False) names the key and value alone (a designer trial: the sag had read as a range
        warning)."""
        if not self.about_range:
            return f"key `{self.key}` = {self.value:g} {self.unit}: {self.reason}"
        where = (f"lies outside {self.low:g}-{self.high:g} {self.unit}" if self.outside else
                 f"(checked range {self.low:g}-{self.high:g} {self.unit})")
        return f"key `{self.key}` = {self.value:g} {self.unit} {where}: {self.reason}"


def linear_model_error_mm(design: RodDesign) -> tuple[float, float]:
    """(self-weight sag [mm], second-order error of the linear models ``sag^2 / reach`` [mm]) by the closed form."""
    _, Cg = calc_compliance(design)
    sag = float(max(np.linalg.norm(Cg @ g) for g in np.eye(3)))        # worst gravity direction, mm per g0
    reach = float(np.linalg.norm(design.tool_mm))
    return sag, sag * sag / max(reach, 1e-9)


#: a tube thinner than this [mm] on a rod that sags beyond the limit is named as the likelier cause (a unit)
THIN_TUBE_MM = 10.0


def _longer_key(design: RodDesign) -> str:
    return "L2_mm" if design.L2_mm >= design.L1_mm else "L1_mm"


def check_design(design: RodDesign) -> None:
    """Refuse a rod beyond linear theory (the rules on parts and lengths are :class:`~rodlab.core.design.RodDesign`'s
    own)."""
    sag, _ = linear_model_error_mm(design)
    reach = float(np.linalg.norm(design.tool_mm))
    if sag > SAG_LIMIT * reach:
        key = _longer_key(design)
        tube = min((design.pipe_I, design.pipe_II), key=lambda t: t.outer_diameter_mm)
        thin = tube.outer_diameter_mm
        if thin < THIN_TUBE_MM:           # designer trials: a tube in cm or inches had been blamed on L2
            raise DesignError(
                f"outer_diameter_mm = {thin:g}: the rod would sag {sag:.3g} mm under its own weight, {sag / reach:.3g} "
                f"x its reach of {reach:.0f} mm (limit {SAG_LIMIT:g}), and its tube is thinner than any measuring "
                f"rod's: {_unit_guess(thin, tube.wall_mm)}sizes are in millimetres", key=f"{tube.key}.outer_diameter_mm")
        raise DesignError(
            f"{key} = {getattr(design, key):g} mm: the rod would sag {sag:.3g} mm under its own weight, "
            f"{sag / reach:.3g} x its reach of {reach:.0f} mm (limit {SAG_LIMIT:g}); it would hang rather than reach "
            f"and the linear compliance models do not describe it; shorten the rod or stiffen its tubes (rods "
            f"checked: {_range_text()})", key=key)


#: the largest tube a measuring rod has [mm] (a unit guess beyond it is no guess)
_LARGEST_TUBE_MM = 120.0


def _unit_guess(od: float, wall: float) -> str:
    """'in centimetres (3 cm = 30 mm) or inches (...)? ' for a tube's size given in another unit, the units that
    give a tube of a measuring rod's size; '' where none does."""
    units = [(u, f) for u, f in (("centimetres", 10.0), ("inches", 25.4)) if THIN_TUBE_MM <= f * od <= _LARGEST_TUBE_MM]
    if not units:
        return ""
    said = " or ".join(f"{u} ({od:g} x {f:g} = {f * od:g} mm, wall {f * wall:.3g} mm)" for u, f in units)
    return f"given in {said}? "



def _range_text() -> str:
    return ", ".join(f"{k} {lo:g}-{hi:g} {u}" for k, (lo, hi, u) in VERIFIED_RANGE.items())


def range_warnings(design: RodDesign) -> list[RangeWarning]:
    """Keys outside :data:`VERIFIED_RANGE`, the ball behind the flange plane, and a linear-model error above
    :data:`LINEAR_WARN_MM`."""
    out = []
    for key, (lo, hi, unit) in VERIFIED_RANGE.items():
        v = float(getattr(design, key))
        if not lo <= v <= hi:
            out.append(RangeWarning(key, v, lo, hi, unit, "the frame model was not checked against solid FEA "
                                    "there; check this design with `rodlab fea --model solid`"))
    z_ball = float(design.tool_mm[2])
    if z_ball < 0.0:
        lo, hi, unit = VERIFIED_RANGE["gamma_deg"]
        out.append(RangeWarning("gamma_deg", design.gamma_deg, lo, hi, unit,
                                f"the ball centre lies {-z_ball:.1f} mm behind the flange plane (L1 - L2 cos(gamma) "
                                f"< 0): pipe II reaches back beside the robot's wrist; check its clearance on your "
                                f"robot over the wrist's range, or increase gamma_deg / L1_mm"))
    out += _thin_wall_warnings(design)
    sag, err = linear_model_error_mm(design)
    if err > LINEAR_WARN_MM:
        key = _longer_key(design)
        lo, hi, unit = VERIFIED_RANGE[key]
        unusable = ("; no linear compliance model brings such a rod to a tracker's accuracy: shorten it or stiffen "
                    "its tubes"
                    if err > 1.0 else "")
        out.append(RangeWarning(key, float(getattr(design, key)), lo, hi, unit,
                                f"the rod sags {sag:.3g} mm under its own weight, so the linear compliance models "
                                f"are off by about {_length(err)} (more than {LINEAR_WARN_MM * 1e3:.0f} um, a "
                                f"tracker's noise){unusable}", about_range=False))
    return out


#: a tube whose outer diameter is more than this many walls is thin-walled beyond any stock measuring-rod tube
THIN_WALL_RATIO = 100.0


def _thin_wall_warnings(design: RodDesign) -> list[RangeWarning]:
    """A warning per tube whose diameter-to-wall ratio exceeds :data:`THIN_WALL_RATIO` (a new-user trial: a 0.05 mm
    wall on a 30 mm tube, D/t 600, passed with a sag warning alone): beam theory and the linear FEA hold no dent,
    local buckling or ovalisation of such a wall at the clamps."""
    out = []
    for tube in {t.key: t for t in (design.pipe_II, design.pipe_I)}.values():     # one per key of the file
        ratio = tube.outer_diameter_mm / tube.wall_mm
        if ratio > THIN_WALL_RATIO:
            out.append(RangeWarning(f"{tube.key}.wall_mm", tube.wall_mm, tube.outer_diameter_mm / THIN_WALL_RATIO,
                                    tube.outer_diameter_mm / 2, "mm",
                                    f"a {tube.outer_diameter_mm:g} mm tube with a {tube.wall_mm:g} mm wall (D/t "
                                    f"{ratio:.0f}) is a foil, not a stock tube (measuring rods' tubes: D/t 5-40): it "
                                    "would dent, buckle locally or ovalise at its clamps and sleeves, which the beam "
                                    "and linear FEA models do not hold; is the wall mistyped?", about_range=False))
    return out


def _length(mm: float) -> str:
    return f"{mm * 1e3:.0f} um" if mm < 1.0 else f"{mm:.3g} mm"


def laminate_bend_warning(design: RodDesign, bend_material_given: bool) -> str | None:
    """A warning where the bend is a fibre laminate only because its material was not given (the tube's, bent to
    the bend's radius: a pultruded or wound carbon tube cannot be bent; a designer trial's rod without ``[bend]``
    had been valid without a word), else None."""
    if bend_material_given or not _laminate(design.bend.material):
        return None
    return (f"no [bend] material: the bend is pipe I's laminate ({design.bend.material.name}) bent to a "
            f"{design.bend.radius_mm:g} mm radius, which a pultruded or wound carbon tube cannot be (the paper's rods "
            "bend a steel pipe joined by rings); give a [bend] of the pipe you will use (docs/formats.md)")


def _laminate(m) -> bool:
    """A fibre laminate: far stiffer along than across (E_transverse below a third of E) or in shear (G below
    half an isotropic material's E / 2(1 + nu))."""
    return ((m.E_transverse_GPa is not None and m.E_transverse_GPa < m.E_GPa / 3.0)
            or (m.G_GPa is not None and m.G_GPa < 0.5 * m.E_GPa / (2.0 * (1.0 + m.nu))))
