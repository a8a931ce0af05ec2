"""The rod's non-repeatable deflection (slip and hysteresis in its joints): what no compliance file removes.

Eq. 19 makes the rod's deflection a function of its load in {T}: the same load, the same deflection. A real rod
is not that elastic: between two measured points the robot turns it, its weight's direction in {T} changes (up
to reversing), and micro-slip in the threaded holders and bonded joints (dry friction), the epoxy's creep and
the settling of the ball in its holder leave it off that deflection by an amount that depends on the load path,
not on the load. Seen from the calibration the offset is random from point to point, and it scales with the
rod's compliance (the same slip moment turns a soft joint further). rodlab models it as the deflection a load
of ``slip`` times the rod's own weight would add, in a random direction, at every point:

    dx_T,i = slip * C_g u_i,   u_i ~ N(0, I / 3)   (|u_i| ~ 1; C_g the true rod's gravity compliance [mm/g0])

It acts with every compensation method (also with the true compliance), so it counts as identification error
in the study's budget.

Size. The paper publishes no hysteresis of the rods, only its consequences: its rig's load-deflection lines
(Fig. 8) cross the load axis at ~1 N on both rods (friction), the carbon rods' r_rod grows with creep in the
bonds (3#: 2.30), and Table 3's rods end above what elastic deflection and the robot's own error explain, the
more the softer the rod (4# Meas 0.451 mm against a laser-scanner floor of 0.263 mm). ``slip`` is fitted to
Table 3 (docs/study.md); the fit is 2.4, i.e. an error more than twice the rod's own gravity deflection: larger
than the elastic hysteresis of bonded joints explains (tens of %), so it stands for all the rod-related error
that grows with compliance and that Eq. 19 does not describe.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.compliance import RodCompliance

from .compensations.rod_deflection import flange_loads
from .kinematics import ModelParams

__all__ = ["slip_offsets", "slip_directions"]


def slip_directions(rng, n: int) -> np.ndarray:
    """The random load directions ``u`` (n, 3) [-] of ``n`` points, ``N(0, I / 3)``."""
    return rng.standard_normal((n, 3)) / np.sqrt(3.0)


def slip_offsets(robot, params: ModelParams, q_rad: np.ndarray, force_W_N: np.ndarray, rod: RodCompliance,
                 slip: float, u: np.ndarray) -> np.ndarray:
    """The slip offsets in {W} [mm], shape=(N, 3), of the rod ``rod`` (its true compliance) in the configurations
    ``q_rad`` (N, n) with load directions ``u`` (N, 3) (:func:`slip_directions`); zero at ``slip`` 0."""
    q = np.atleast_2d(np.asarray(q_rad, float))
    if slip == 0 or not rod.C_g.any():
        return np.zeros((q.shape[0], 3))
    F = np.broadcast_to(np.asarray(force_W_N, float), (q.shape[0], 3))
    R_TW, _, _ = flange_loads(robot, params, q, F, rod)
    return float(slip) * np.einsum("nij,jk,nk->ni", R_TW, rod.C_g, np.asarray(u, float))
