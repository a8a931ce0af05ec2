"""What every rig effect provides: its parameter schema, its forward model (hooks the rig model calls in a
fixed order), its hypotheses for the diagnosis and its wording. One subclass per effect, one module each.

Forward model of a reading (``RigModel.reading``), each hook applied by every active effect in registry order:

1. ``compliance`` — the rod's true C_F from the simulated one (structural effects);
2. ``mass`` then ``force`` — the load that reaches the ball (tare, friction); ``load_line`` — its direction
   (a load line tilted off the hold's axis: crosstalk's load form);
3. ``load_compliance`` — a compliance that depends on the load or the branch (nonlinearity, hysteresis);
4. ``deflection`` — time-dependent deflection with state (creep);
5. ``reading`` — what the gauges make of it (crosstalk, drift).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from rodlab.core.hypothesis import EffectSchema, Hypothesis

from ..errors import RigError

if TYPE_CHECKING:                       # the registry builds the Enum from the effect modules
    from . import RigEffect

__all__ = ["RigEffectModel", "HypothesisContext", "RigState"]


@dataclass(frozen=True)
class HypothesisContext:
    """What hypotheses are built from, besides the samples.

    C_sim : simulated C_F [mm/N], shape=(3, 3); base : simulated displacement of every sample [mm], shape=(n,);
    places : {location: (point in {T} [mm], member axis in {T})} of candidate compliant joints;
    tool_mm : ball centre in {6} [mm], shape=(3,)
    """

    C_sim: np.ndarray
    base: np.ndarray
    places: dict
    tool_mm: np.ndarray


@dataclass
class RigState:
    """Mutable state of the forward model: the deflection [mm] in {T} of each creep term, shape=(2, 3), the time of
    the last reading [s], the creep each term was approaching then [mm], shape=(2, 3), and where each gauge's
    plunger sits against the rod with its play [mm], shape=(3,) (None before a series' first reading)."""

    creep: np.ndarray = field(default_factory=lambda: np.zeros((2, 3)))
    t_last: float | None = None
    creep_target: np.ndarray = field(default_factory=lambda: np.zeros((2, 3)))
    gauge_contact: np.ndarray | None = None


class RigEffectModel(EffectSchema):
    """One rig effect. Subclasses set the class attributes and override the hooks they need.

    effect : its ID (the registry makes it its ``RigEffect`` member); order : its place in the registry (an int
    of its own); params : its parameters (names and units shared by simulator, report and docs);
    example : the parameters ``--effect NAME`` gives when no magnitude is stated; physics : what is left out
    (help text); signature : how it shows in the data; confirm : the measurement that would confirm a finding;
    structural : it changes the rod's compliance (kept in a corrected compliance file); locations : its
    location keys in a diagnosis
    """

    effect: RigEffect     # written as its contract spelling, ``effect = "friction"``
    order: int            # e.g. ``order = 10``: where the forward model applies it and the diagnosis lists it
    params: tuple = ()
    example: dict = {}
    physics: str = ""
    signature: str = ""
    confirm: str = ""
    structural: bool = False
    locations: tuple = ()

    def fail(self, message: str, key: str) -> None:
        raise RigError(message, key=key)

    # -- forward model (identity unless overridden) ------------------------------------------------------------
    def compliance(self, C: np.ndarray, p: dict, places: dict) -> np.ndarray:
        return C

    def mass(self, m: float, hold, p: dict) -> float:
        return m

    def force(self, F: float, hold, p: dict) -> float:
        return F

    def load_line(self, F: np.ndarray, hold, p: dict) -> np.ndarray:
        """The force vector [N] in {T} on the ball, from the one along the hold's axis ``F``."""
        return F

    def load_compliance(self, C: np.ndarray, F: np.ndarray, hold, p: dict) -> np.ndarray:
        return C

    def with_plan(self, p: dict, masses) -> dict:
        """The parameters ``p`` with what the load plan sets (its ``masses`` [kg]) filled in where not given."""
        return p

    def deflection(self, x: np.ndarray, C: np.ndarray, F: np.ndarray, t: float, state: RigState,
                   p: dict) -> np.ndarray:
        return x

    def reading(self, x: np.ndarray, t: float, dtemp_K: float, p: dict) -> np.ndarray:
        return x

    # -- diagnosis ---------------------------------------------------------------------------------------------
    def confirm_for(self, location: str | None) -> str:
        """What would confirm a finding of this effect at ``location`` (the effect's sentence unless a form of it
        needs another)."""
        return self.confirm

    def caution(self, p: dict) -> str | None:
        """A warning for fitted parameters ``p`` that no rod or rig of this kind has (a units slip, another
        rod's data), or None."""
        return None

    def place_caution(self, location: str | None) -> str | None:
        """A warning a finding of this effect at ``location`` needs whatever its size (a place that may be the
        rig's, not the rod's), or None."""
        return None

    def hypotheses(self, data, ctx: HypothesisContext) -> list[Hypothesis]:
        """Candidate terms of this effect for the samples ``data`` (:class:`~rodlab.stiffness_rig.RigSamples`)."""
        return []

    def place(self, p: dict, places: dict, location: str) -> tuple:
        """(point in {T}, axis) of a spring: ``point_T_mm`` / ``axis`` when given, else the named place."""
        if "point_T_mm" in p and "axis" in p:
            return np.asarray(p["point_T_mm"], float), np.asarray(p["axis"], float)
        if location not in places:
            raise RigError(f"effect {self.effect}: no place {location!r} on this rod (known: {sorted(places)}); give "
                           f"point_T_mm and axis", key=f"{self.effect}.location")
        pt, ax = places[location]
        return np.asarray(p.get("point_T_mm", pt), float), np.asarray(p.get("axis", ax), float)
