"""The compensation interface: what every compensation of a measured ball centre provides.

A compensation models one effect of the rod that moves the ball centre away from where the rigid model puts it
(the rod's deflection, its thermal growth, ...) as ball-centre offsets in {W} [mm], one per point, computed from
the current robot model. Identification (:func:`~rodlab.calibrate.identify.identify`) removes the offsets of its
``compensations`` from the measurements, alternating with the fit until they stop changing (paper Eqs. 11-19);
the simulator (:func:`~rodlab.calibrate.simulate.simulate_campaign`) adds the true rod's to its readings.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from ..rod import Rod

__all__ = ["Compensation", "Poses"]


@dataclass(frozen=True)
class Poses:
    """Where a compensation's offsets are wanted, when they are not an identification's
    :class:`~rodlab.calibrate.identify.Observations` (which has the same fields).

    q_rad : joint angles [rad], shape=(N, n); force_W_N : contact force on the ball in {W} [N], shape=(N, 3) (zero
    when not given); temp_C : temperature of each point [degC], shape=(N,), or None; rod : the rod
    (:class:`~rodlab.calibrate.rod.Rod`), whose weight bends the joints a little, or None
    """

    q_rad: np.ndarray
    force_W_N: np.ndarray | None = None
    temp_C: np.ndarray | None = None
    rod: Rod | None = None

    def __post_init__(self) -> None:
        q = np.atleast_2d(np.asarray(self.q_rad, float))
        object.__setattr__(self, "q_rad", q)
        F = np.zeros((q.shape[0], 3)) if self.force_W_N is None else self.force_W_N
        object.__setattr__(self, "force_W_N", np.broadcast_to(np.asarray(F, float), (q.shape[0], 3)))
        if self.temp_C is not None:
            t = np.asarray(self.temp_C, float)
            if t.shape != (q.shape[0],):
                raise ValueError(f"temp_C must have shape ({q.shape[0]},), got {t.shape}")
            object.__setattr__(self, "temp_C", t)
        if self.rod is not None and not isinstance(self.rod, Rod):
            raise TypeError(f"Poses.rod must be a Rod or None, got {type(self.rod).__name__}")


class Compensation(ABC):
    """One compensation (an entry of :data:`~rodlab.calibrate.compensations.COMPENSATIONS`).

    Class attributes (the registry's help and docs tables come from them): ``name`` the ID; ``summary`` what it
    removes; ``needs`` the data it needs; ``option`` how ``rodlab calibrate`` turns it on. Instances have a
    ``label`` (shown in results: the result file's ``compensation`` joins the active ones' labels with ``+``).
    """

    name: ClassVar[str]
    summary: ClassVar[str]
    needs: ClassVar[str]
    option: ClassVar[str]

    @property
    def active(self) -> bool:
        """True when it changes the measurements."""
        return True

    @property
    def rough_pass(self) -> bool:
        """True when the first identification pass must hold the joint compliances at their initial values
        (paper Section 4.1: else the wrist's compliance absorbs what this compensation has not yet removed)."""
        return False

    @classmethod
    def truth_of(cls, entry: "Compensation | None") -> dict:
        """Its keys of a simulated campaign's ``truth.json``: what ``entry`` simulated, or (``None``) the same keys
        empty when the campaign did not simulate it (every truth file has every key)."""
        return {}

    @abstractmethod
    def offsets(self, robot, params, at) -> np.ndarray:
        """Ball-centre offsets in {W} [mm], shape=(N, 3), of the robot ``params`` at the points ``at``
        (:class:`~rodlab.calibrate.identify.Observations` or :class:`Poses`)."""
