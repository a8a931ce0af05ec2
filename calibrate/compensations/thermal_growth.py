"""Thermal growth of the measuring rod as a compensation (beside the rod's deflection).

The tool vector (flange to ball centre) of a rod grows with its temperature by ``g (T - T_ref)``, where
``g`` [mm/K] in {T} is the sum over the rod's members of each member's axial CTE times its span
(:func:`rodlab.core.strength.thermal_growth_um_per_K`): about 8 um/K for a 500 mm steel rod, a tenth of that for
carbon. A campaign whose ``temp_C`` changes while the robot measures sees each point's ball centre moved by
that growth, rotated to {W} with the flange (Eq. 11 as for deflection); a constant temperature only shifts the
tool, which identification absorbs. Needs the campaign's ``temp_C`` column.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rodlab.core.strength import thermal_growth_um_per_K

from ..errors import CalibrationError
from ..kinematics import ModelParams, ball_positions
from ..rod import Rod
from .base import Compensation

__all__ = ["ThermalGrowth", "tool_axes_W"]


def tool_axes_W(robot, params: ModelParams, q_rad: np.ndarray, force_W_N=None, rod: Rod | None = None) -> np.ndarray:
    """Rotation of {T} (the flange axes) in {W}, shape=(N, 3, 3), at configurations ``q_rad`` (N, n) under the
    weight of ``rod`` and the contact forces (the joints' compliance turns the flange a little)."""
    q = np.atleast_2d(np.asarray(q_rad, float))
    F = np.zeros((q.shape[0], 3)) if force_W_N is None else np.broadcast_to(np.asarray(force_W_N, float),
                                                                             (q.shape[0], 3))
    fr, _ = ball_positions(robot, params, q, rod, force_W_N=F)
    return fr.R_W0[None] @ fr.T[:, robot.n, :3, :3]


@dataclass(frozen=True)
class ThermalGrowth(Compensation):
    """The rod's tool vector growing with temperature.

    growth_T_mm_per_K : shift of the ball centre per kelvin in {T} [mm/K], shape=(3,)
    T_ref_C : the temperature the tool vector is stated at [degC]
    label : the name shown in results
    """

    name: ClassVar[str] = "thermal_growth"
    summary: ClassVar[str] = ("the rod's tool vector growing with its temperature: each member's axial CTE times its "
                              "span, per kelvin from the reference, rotated to {W} with the flange")
    needs: ClassVar[str] = "the campaign's temp_C column and the rod's design (its materials' cte_ppm_K)"
    option: ClassVar[str] = "`--thermal DESIGN` (`--t-ref-c` the reference temperature)"

    growth_T_mm_per_K: np.ndarray
    T_ref_C: float = 20.0
    label: str = "thermal"

    def __post_init__(self) -> None:
        g = np.asarray(self.growth_T_mm_per_K, float)
        if g.shape != (3,) or not np.all(np.isfinite(g)):
            raise CalibrationError(f"the rod's thermal growth must be 3 finite numbers [mm/K] in {{T}}, got "
                                   f"{self.growth_T_mm_per_K!r}; every tube and the ball need a material with "
                                   f"cte_ppm_K", key="thermal")
        if not np.isfinite(self.T_ref_C):
            raise CalibrationError(f"the reference temperature must be finite, got {self.T_ref_C!r}", key="t_ref_C")
        object.__setattr__(self, "growth_T_mm_per_K", g)

    @classmethod
    def of_design(cls, design, T_ref_C: float = 20.0) -> "ThermalGrowth":
        """From a rod design: each member's axial CTE (the materials table) times its span."""
        g = np.asarray(thermal_growth_um_per_K(design), float) * 1e-3
        if not np.all(np.isfinite(g)):
            raise CalibrationError(f"design {design.name}: a tube or the ball has a material without cte_ppm_K; "
                                   f"add it to the materials table to compensate thermal growth", key="cte_ppm_K")
        return cls(g, float(T_ref_C))

    @property
    def active(self) -> bool:
        return bool(self.growth_T_mm_per_K.any())

    @classmethod
    def truth_of(cls, entry: "ThermalGrowth | None") -> dict:
        return {"rod_thermal_growth_T_mm_per_K": None if entry is None else entry.growth_T_mm_per_K.tolist()}

    def offsets(self, robot, params: ModelParams, at) -> np.ndarray:
        """Ball-centre offsets in {W} [mm], shape=(N, 3), at the points ``at``
        (:class:`~rodlab.calibrate.identify.Observations` or :class:`~.base.Poses` with ``temp_C`` [degC])."""
        if at.temp_C is None or not np.all(np.isfinite(at.temp_C)):
            raise CalibrationError("thermal compensation needs the temperature of every point: a temp_C column in "
                                   "the campaign", key="temp_C")
        R = tool_axes_W(robot, params, at.q_rad, at.force_W_N, at.rod)
        dx_T = np.outer(np.asarray(at.temp_C, float) - self.T_ref_C, self.growth_T_mm_per_K)
        return np.einsum("nij,nj->ni", R, dx_T)
