"""What the measuring rod brings to a calibration, as one value: its tool vector, mass, centre of mass and
compliance (paper Eqs. 10-19), and the method the compliance came from.

A compliance file (:class:`rodlab.RodCompliance`) carries all of it plus its provenance; instrument points carry
only a tool and a payload (a rigid rod). Identification (:func:`~rodlab.calibrate.identify.identify`), the rod's
deflection compensation (:class:`~rodlab.calibrate.compensations.RodDeflection`) and the simulator take a
:class:`Rod`, so the rod travels one way instead of as a wrapped file, a separate tool and loose scalars.
"""
from __future__ import annotations


from dataclasses import dataclass

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method
from rodlab.core.errors import expect_type

from .errors import CalibrationError

__all__ = ["Rod"]


def _vector(value, key: str) -> np.ndarray:
    a = np.asarray(value, float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise CalibrationError(f"the rod's {key} must be 3 finite numbers [mm], got {value!r}", key=key)
    return a


def _matrix(value, key: str) -> np.ndarray:
    a = np.asarray(value, float)
    if a.shape != (3, 3) or not np.all(np.isfinite(a)):
        raise CalibrationError(f"the rod's {key} must be a finite 3x3 matrix, got shape {a.shape}", key=key)
    return a


@dataclass(frozen=True)
class Rod:
    """The rod on the flange, as a calibration sees it.

    tool_mm : ball centre in the flange frame {n} (= {T}) [mm], shape=(3,)
    mass_kg : the rod's mass [kg] (its weight loads the joints), >= 0
    com_T_mm : its centre of mass in {T} [mm], shape=(3,)
    C_F : ball-centre displacement per contact force on the ball [mm/N], in {T}, shape=(3, 3) (Eq. 19)
    C_g : ball-centre displacement under the rod's own weight per g0 of gravity [mm/g0], in {T}, shape=(3, 3)
    method : where ``C_F`` / ``C_g`` came from (:class:`rodlab.core.enums.Method`; ``none``: a rigid rod)
    name : the rod's name (the compliance file's ``rod``), for messages
    """

    tool_mm: np.ndarray
    mass_kg: float = 0.0
    com_T_mm: np.ndarray = (0.0, 0.0, 0.0)
    C_F: np.ndarray = ((0.0,) * 3,) * 3
    C_g: np.ndarray = ((0.0,) * 3,) * 3
    method: Method = Method.NONE
    name: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "tool_mm", _vector(self.tool_mm, "tool_mm"))
        object.__setattr__(self, "com_T_mm", _vector(self.com_T_mm, "com_T_mm"))
        object.__setattr__(self, "C_F", _matrix(self.C_F, "C_F"))
        object.__setattr__(self, "C_g", _matrix(self.C_g, "C_g"))
        if not (np.isfinite(self.mass_kg) and self.mass_kg >= 0):
            raise CalibrationError(f"the rod's mass must be a finite number >= 0 [kg], got {self.mass_kg!r}",
                                   key="mass_kg")
        object.__setattr__(self, "mass_kg", float(self.mass_kg))
        object.__setattr__(self, "method", Method(self.method))

    @classmethod
    def of(cls, compliance: RodCompliance) -> "Rod":
        """The rod a compliance file describes (tool, mass, COM, matrices, method)."""
        expect_type(compliance, RodCompliance, "compliance", "a compliance file: rodlab.calc_rod_compliance(design), "
                    "rodlab.read_compliance(FILE) or rodlab.fea.compute_compliance(design)")
        return cls(compliance.tool_mm, compliance.mass_kg, compliance.com_T_mm, compliance.C_F, compliance.C_g,
                   compliance.method, compliance.rod)

    @classmethod
    def rigid(cls, tool_mm, mass_kg: float = 0.0, com_T_mm=(0.0, 0.0, 0.0), name: str = "") -> "Rod":
        """A rod that does not deflect (instrument points, a short probe): tool and payload only."""
        return cls(tool_mm, mass_kg, com_T_mm, name=name)

    @property
    def deflects(self) -> bool:
        """True when its compliance is not zero (the deflection compensation changes the measurements)."""
        return bool(self.C_F.any() or self.C_g.any())

    def offset_T_mm(self, g_T_g0: np.ndarray, F_T_N: np.ndarray) -> np.ndarray:
        """Ball-centre offset (Eq. 19) in {T} [mm], shape=(n, 3), from gravity [g0] and force [N] in {T},
        shape=(n, 3)."""
        g = np.atleast_2d(np.asarray(g_T_g0, dtype=float))
        f = np.atleast_2d(np.asarray(F_T_N, dtype=float))
        return g @ self.C_g.T + f @ self.C_F.T
