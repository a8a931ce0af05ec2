"""Instrument points (a tracker's, a CMM's): their observations and their identification.

The points are measured in the instrument's frame with a target whose place on the flange is only roughly
known, so base and tool are found from scratch and the tool's azimuth about the last axis is free
(``tool_y``); the residuals are judged against the instrument's noise (default :data:`TRACKER_NOISE_MM`).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from rodlab.core.units import TRACKER_NOISE_MM

from .points_file import PointSet
from .crossval import cross_validate_identify
from .estimate import FitOptions
from .identify import Observations, identify
from .result import CalibrationResult
from .rod import Rod

__all__ = ["points_rod", "points_observations", "identify_points", "stated_noise_mm", "cross_validate_points"]


def points_rod(pts: PointSet) -> Rod:
    """The instrument's rigid probe: the file's tool and payload."""
    return pts.rod


def points_observations(pts: PointSet) -> Observations:
    """The identification's observations of instrument points (no contact force, the file's payload)."""
    return Observations(np.deg2rad(pts.q_deg), pts.x_W_mm, np.zeros_like(pts.x_W_mm), pts.rod, sigma_mm=pts.sigma_mm)


def stated_noise_mm(pts: PointSet, noise_mm: float | None) -> tuple[PointSet, float]:
    """The points and the noise level to judge them by: a level the user states (``noise_mm``, replacing any
    per-point columns); else the rms of the file's per-point uncertainties; else :data:`TRACKER_NOISE_MM`."""
    if noise_mm:
        return replace(pts, sigma_mm=None), float(noise_mm)
    if pts.sigma_mm is not None:
        return pts, float(np.sqrt(np.mean(pts.sigma_mm ** 2)))
    return pts, TRACKER_NOISE_MM


def identify_points(robot, pts: PointSet, expected_noise_mm: float | None = TRACKER_NOISE_MM, *,
                    pinned: dict | None = None, freed=(), robust: bool = False,
                    fix_unidentifiable: bool = False, harmonics=()) -> CalibrationResult:
    """Identify ``robot`` from instrument points: base and tool from scratch, ``tool_y`` free; ``None`` noise
    skips the residual test; ``harmonics``: joints whose periodic angle errors are identified too."""
    options = FitOptions(pinned=dict(pinned or {}), freed=set(freed) | {"tool_y"}, robust=robust,
                         fix_unidentifiable=fix_unidentifiable, find_tool=True, expected_noise_mm=expected_noise_mm,
                         harmonics=tuple(harmonics))
    return identify(robot, points_observations(pts), points_rod(pts), options=options)


def cross_validate_points(robot, pts: PointSet, fit_rms_mm: float, *, pinned: dict | None = None, freed=(),
                          robust: bool = False, harmonics=()):
    """The predicted accuracy of :func:`identify_points` with these options without a validation set: k-fold
    cross-validation over the points (:func:`calibrate.crossval.cross_validate_identify`)."""
    options = FitOptions(pinned=dict(pinned or {}), freed=set(freed) | {"tool_y"}, robust=robust, find_tool=True,
                         harmonics=tuple(harmonics))
    return cross_validate_identify(robot, points_observations(pts), points_rod(pts), options=options,
                                   fit_rms_mm=fit_rms_mm)
