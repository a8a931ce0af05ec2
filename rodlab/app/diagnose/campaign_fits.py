"""The identifications behind a campaign diagnosis (:func:`~.campaign.diagnose_campaign`), for its figures,
reports and validation."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["CampaignFits"]


@dataclass
class CampaignFits:
    """The identifications behind a campaign diagnosis (for figures and reports).

    Attributes
    ----------
    before : the :class:`~rodlab.calibrate.CalibrationResult` of the campaign as given
    after : the identification with the found physics, or ``None`` when nothing was found
    kept : shape=(N,) bool, the campaign points ``after`` used (isolated outliers dropped)
    labels : shape=(N,) point labels; position : shape=(N,) int, clamping position of each point
    joint_corrections_rad : {joint index (0-based): (a_sin, a_cos[, b_sin, b_cos]) [rad]} of periodic joint errors found
    validation_errors_mm : {"nominal" | "before" | "after": shape=(M,) [mm]} at the validation points, or None
    q_deg : shape=(N, n) joint angles of the campaign points [deg]
    time_s : shape=(N,) time of each point [s], or None when the campaign has no ``time_s`` column
    torque_corrections : {joint index (0-based): :class:`~rodlab.calibrate.effects.joint_stiffening.TorqueCorrection`}
    of non-linear joint springs found
    """

    before: object
    after: object | None
    kept: np.ndarray
    labels: list
    position: np.ndarray
    joint_corrections_rad: dict
    validation_errors_mm: dict | None = None
    q_deg: np.ndarray | None = None
    time_s: np.ndarray | None = None
    torque_corrections: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = len(self.labels)
        if self.kept.shape != (n,) or self.position.shape != (n,):
            raise ValueError(f"kept and position must have shape ({n},), got {self.kept.shape}, {self.position.shape}")
        if self.q_deg is not None and (self.q_deg.ndim != 2 or self.q_deg.shape[0] != n):
            raise ValueError(f"q_deg must have shape ({n}, n_joints), got {self.q_deg.shape}")
        if self.time_s is not None and self.time_s.shape != (n,):
            raise ValueError(f"time_s must have shape ({n},), got {self.time_s.shape}")
