"""The rod's deflection (paper Eqs. 10-19) as a compensation: the ball-centre offsets ``dx^W`` [mm] that the rod's
deflection under its weight and the contact force adds to each measured point (Eq. 11). The paper's methods
None / Calc / FEA / Meas differ only in the data: the rod's compliance (``C_F``, ``C_g``, Eq. 19, from a
compliance file) the offsets are computed from, or none.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method
from rodlab.core.units import G0

from ..kinematics import ModelParams, ball_positions
from ..rod import Rod
from .base import Compensation

__all__ = ["RodDeflection", "deflection_offsets", "deflection_basis", "flange_loads"]


def deflection_offsets(robot, params: ModelParams, q_rad: np.ndarray, force_W_N: np.ndarray,
                       rod: Rod | RodCompliance | None) -> np.ndarray:
    """Ball-centre offsets in {W} [mm], shape=(N, 3), of a rod with compliance ``rod`` on the robot ``params``
    in configurations ``q_rad`` (N, n) under contact forces ``force_W_N`` (N, 3) in {W}: gravity and force in
    {T} (the flange axes), Eq. 19 in {T}, rotated to {W} (Eq. 11). Zero without a rod or with zero matrices."""
    q = np.atleast_2d(np.asarray(q_rad, float))
    if rod is None or (not rod.C_F.any() and not rod.C_g.any()):
        return np.zeros((q.shape[0], 3))
    R_TW, g_T, F_T = flange_loads(robot, params, q, force_W_N, rod)
    dx_T = rod.offset_T_mm(g_T, F_T)                                   # Eq. 19
    return np.einsum("nij,nj->ni", R_TW, dx_T)                         # Eq. 11 (in {W})


def flange_loads(robot, params: ModelParams, q_rad: np.ndarray, force_W_N: np.ndarray, rod: Rod | RodCompliance | None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """What Eq. 19 multiplies, per configuration: ``R_T^W`` (N, 3, 3) the flange axes in {W}, gravity in {T}
    [g0] (N, 3) and the contact force in {T} [N] (N, 3), with the weight of ``rod`` (a compliance file's mass and
    centre of mass count the same) on the compliant joints."""
    q = np.atleast_2d(np.asarray(q_rad, float))
    F = np.broadcast_to(np.asarray(force_W_N, float), (q.shape[0], 3))
    fr, _ = ball_positions(robot, params, q, _as_rod(rod), force_W_N=F)
    n = robot.n
    R_TW = fr.R_W0[None] @ fr.T[:, n, :3, :3]                        # {T} axes = {n} axes
    g_T = np.einsum("nji,j->ni", fr.T[:, n, :3, :3], robot.gravity_base / G0)
    F_T = np.einsum("nji,nj->ni", R_TW, F)
    return R_TW, g_T, F_T


def deflection_basis(robot, params: ModelParams, q_rad: np.ndarray, force_W_N: np.ndarray,
                     rod: Rod | RodCompliance | None) -> np.ndarray:
    """d (ball-centre offsets in {W}) / d (C_F, C_g) [mm per mm/N, mm per mm/g0], shape=(N, 3, 18): the offsets
    are linear in the compliance (Eq. 19), ``offsets = basis @ concatenate([C_F.ravel(), C_g.ravel()])``."""
    R_TW, g_T, F_T = flange_loads(robot, params, q_rad, force_W_N, rod)
    dF = np.einsum("nik,nl->nikl", R_TW, F_T).reshape(R_TW.shape[0], 3, 9)
    dg = np.einsum("nik,nl->nikl", R_TW, g_T).reshape(R_TW.shape[0], 3, 9)
    return np.concatenate([dF, dg], axis=2)


def _as_rod(rod: Rod | RodCompliance | None) -> Rod | None:
    return Rod.of(rod) if isinstance(rod, RodCompliance) else rod


@dataclass(frozen=True)
class RodDeflection(Compensation):
    """The rod's deflection under its weight and the contact force (Eq. 19), from its compliance.

    rod : the rod (:class:`~rodlab.calibrate.rod.Rod`) whose ``C_F`` / ``C_g`` give the offsets; ``None`` = no
        compensation
    label : the name shown in results and reports (e.g. ``fea``, ``meas``, ``corrected``)
    """

    name: ClassVar[str] = "rod_deflection"
    summary: ClassVar[str] = ("the rod's deflection under its weight and the contact force (paper Eq. 19): "
                              "C_g g^T + C_F F^T, rotated to {W}")
    needs: ClassVar[str] = "the rod's compliance file (C_F, C_g; method calc / fea / meas)"
    option: ClassVar[str] = "`--rod FILE` (`--compensation file`, the default; `none` leaves it out)"

    rod: Rod | None = None
    label: str = str(Method.NONE)

    def __post_init__(self) -> None:
        if not isinstance(self.label, str) or not self.label.strip():
            raise ValueError(f"a compensation needs a non-empty label, got {self.label!r}")
        if self.rod is not None and not isinstance(self.rod, Rod):
            raise TypeError(f"rod must be a Rod or None, got {type(self.rod).__name__}")

    @classmethod
    def of(cls, rod: Rod | RodCompliance | None, label: str | None = None) -> "RodDeflection":
        """The compensation a rod (or its compliance file) stands for, labelled by its method unless ``label`` is
        given; a rod of method ``none`` (zero matrices) is no compensation."""
        if rod is None:
            return cls(None, label or str(Method.NONE))
        rod = Rod.of(rod) if isinstance(rod, RodCompliance) else rod
        return cls(None if rod.method is Method.NONE else rod, label or str(rod.method))

    @property
    def active(self) -> bool:
        """True when it changes the measurements (a rod with non-zero compliance)."""
        return self.rod is not None and self.rod.deflects

    @property
    def rough_pass(self) -> bool:
        return self.active

    def offsets(self, robot, params: ModelParams, at) -> np.ndarray:
        """Ball-centre offsets in {W} [mm], shape=(N, 3) (see :func:`deflection_offsets`)."""
        return deflection_offsets(robot, params, at.q_rad, at.force_W_N, self.rod if self.active else None)
