"""The calibrator's robot: DH rows with Hayati's beta, joint limits, link masses (from any description).

``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i)``, ``theta_i = q_i + theta_offset_i``;
link i's mass and centre of mass (in frame i, at the end of the link) feed the static joint torques. Robot
descriptions (rodlab TOML with DH / modified-DH rows, URDF) are read by :mod:`calibrate.robot_formats`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .robot_lines import NEAR_PARALLEL_DEG, ZeroChain, chain_matrices, dh_rows

__all__ = ["Robot", "robot_from_chain", "dh_zero_chain"]


@dataclass(frozen=True)
class Robot:
    """A serial robot.

    Attributes (n = number of joints)
    ---------------------------------
    name; theta_offset_deg, d_mm, a_mm, alpha_deg, beta_deg : shape=(n,) nominal DH rows [deg, mm]
    limits_deg : shape=(n, 2); mass_kg : shape=(n,); com_mm : shape=(n, 3) in frame i
    gravity_base : shape=(3,) [m/s^2] in {0}
    base_T_0 : shape=(4, 4) [mm], {0} in the description's base frame (URDF root link; identity for DH rows)
    n_T_tip : shape=(4, 4) [mm], the description's tip frame (flange / tool0) in {n}
    joint_names : the description's joint names (``joint_1`` ... by default); source : where it came from
    """

    name: str
    theta_offset_deg: np.ndarray
    d_mm: np.ndarray
    a_mm: np.ndarray
    alpha_deg: np.ndarray
    beta_deg: np.ndarray
    limits_deg: np.ndarray
    mass_kg: np.ndarray
    com_mm: np.ndarray
    gravity_base: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, -9.80665]))
    path: Path | None = field(default=None, compare=False)
    base_T_0: np.ndarray = field(default_factory=lambda: np.eye(4), compare=False)
    n_T_tip: np.ndarray = field(default_factory=lambda: np.eye(4), compare=False)
    joint_names: tuple = ()
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        n = self.n
        for k in ("d_mm", "a_mm", "alpha_deg", "beta_deg", "mass_kg"):
            if np.shape(getattr(self, k)) != (n,):
                raise ValueError(f"{k} must have shape ({n},)")
        if np.shape(self.limits_deg) != (n, 2) or np.shape(self.com_mm) != (n, 3):
            raise ValueError("limits_deg must be (n, 2) and com_mm (n, 3)")
        if np.shape(self.base_T_0) != (4, 4) or np.shape(self.n_T_tip) != (4, 4):
            raise ValueError("base_T_0 and n_T_tip must be 4x4")
        if not self.joint_names:
            object.__setattr__(self, "joint_names", tuple(f"joint_{i + 1}" for i in range(n)))
        if len(self.joint_names) != n:
            raise ValueError(f"joint_names must name {n} joints, got {len(self.joint_names)}")

    @property
    def n(self) -> int:
        return int(np.shape(self.theta_offset_deg)[0])

    def parallel_rows(self) -> list[int]:
        """Rows (0-based) whose joint axis is parallel to the next one, within ``NEAR_PARALLEL_DEG`` (the tilt
        ``Rx(alpha) Ry(beta)`` turns z by less; Hayati's rows), the next row existing."""
        tilt = np.cos(np.deg2rad(self.alpha_deg)) * np.cos(np.deg2rad(self.beta_deg))
        return [i for i in range(self.n - 1) if abs(tilt[i]) > math.cos(math.radians(NEAR_PARALLEL_DEG))]


def robot_from_chain(chain: ZeroChain, joint_names=(), path=None) -> Robot:
    """The calibrator's exact model of a chain given by its axes at q = 0 (:func:`calibrate.robot_lines.dh_rows`)."""
    rows = dh_rows(chain)
    gravity_0 = rows.base_T_0[:3, :3].T @ chain.gravity
    return Robot(chain.name, rows.theta_offset_deg, rows.d_mm, rows.a_mm, rows.alpha_deg, rows.beta_deg,
                 np.asarray(chain.limits_deg, float), np.asarray(chain.link_mass_kg, float), rows.com_mm,
                 gravity_base=gravity_0, path=None if path is None else Path(path), base_T_0=rows.base_T_0,
                 n_T_tip=rows.n_T_tip, joint_names=tuple(joint_names), source=chain.source)


def dh_zero_chain(robot: Robot) -> ZeroChain:
    """The chain of a robot's own rows at q = 0 in {0} (for tests and conversions back and forth)."""
    F = chain_matrices(robot.theta_offset_deg, robot.d_mm, robot.a_mm, robot.alpha_deg, robot.beta_deg)
    com = np.einsum("nij,nj->ni", F[1:], np.c_[robot.com_mm, np.ones(robot.n)])[:, :3]
    return ZeroChain(robot.name, F[:-1, :3, 3].copy(), F[:-1, :3, 2].copy(), F[-1] @ robot.n_T_tip,
                     robot.limits_deg, robot.mass_kg, com, robot.gravity_base, robot.source)
