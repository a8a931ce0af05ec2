"""Calibrate the frame model on a design family (one tube / bend / sleeve set, any L1 x L2) from solid FEA.

The global calibration (:data:`fea.frame.CALIBRATION`) is a compromise over many materials and joints; on
random designs it can be several per cent off (docs/fea.md). Within a family the joints are the same and only
the lever arms change, so a few solid runs pin the family's own constants:

- one solid run (the base design) fits the two bend factors (:data:`fea.frame.FAMILY_FIT`): enough on the
  paper's families (within 0.73 %), not on families whose mismatch lies in the joints (up to 4 % on random
  ones);
- two solid runs far apart in L1 x L2 (the base and the sweep's design farthest from it) fit the bend factors
  and the holder and sleeve load-transfer zones (:data:`FAMILY_FIT_TWO`): the changed lever arms separate the
  joints from the bend. On 10 random families chosen for their large errors this left at most 1.1 % on a
  third member (``scripts/frame_random_blind.py``).
"""
from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from typing import Callable

import numpy as np

from rodlab.design import RodDesign
from rodlab.errors import RodlabError

from .frame import FAMILY_FIT, FrameCalibration, calibrate_frame, frame_errors

__all__ = ["FAMILY_FIT_TWO", "FamilyCalibration", "family_partner", "calibrate_family"]

log = logging.getLogger(__name__)

#: the constants refitted from two solid runs of one family
FAMILY_FIT_TWO = FAMILY_FIT + ("holder_end", "sleeve_end")


@dataclass(frozen=True)
class FamilyCalibration:
    """A frame calibration fitted on solid runs of one family.

    calibration : the fitted constants; names : which ones were fitted; designs : the solid-run designs;
    max_err : largest relative error [-] of the calibrated frame on each of them (every entry above 2 % of
    its matrix's largest, C_F and C_g).
    """

    calibration: FrameCalibration
    names: tuple[str, ...]
    designs: tuple[RodDesign, ...]
    max_err: tuple[float, ...]


def family_partner(base: RodDesign, L1s, L2s) -> RodDesign | None:
    """The valid design of the L1 x L2 grid farthest from ``base`` (relative distance
    ``|dL1| / L1 + |dL2| / L2``), or None if no grid design other than the base is valid."""
    best, best_d = None, 0.0
    for L1 in np.asarray(L1s, dtype=float):
        for L2 in np.asarray(L2s, dtype=float):
            dist = abs(L1 - base.L1_mm) / base.L1_mm + abs(L2 - base.L2_mm) / base.L2_mm
            if dist <= best_d + 1e-12:
                continue
            try:
                d = replace(base, L1_mm=float(L1), L2_mm=float(L2), name=f"{base.name} {L1:g}-{L2:g}")
            except RodlabError:
                continue
            best, best_d = d, dist
    if best is not None and best_d < 0.05:
        return None                               # too close to the base to separate the joints from the bend
    return best


def calibrate_family(base: RodDesign, solve: Callable[[RodDesign], tuple[np.ndarray, np.ndarray]],
                     partner: RodDesign | None = None) -> FamilyCalibration:
    """Fit the frame to ``solve(design) -> (C_F, C_g)`` (solid FEA) of ``base`` and, if given, ``partner``
    (another L1 x L2 member of the family, e.g. :func:`family_partner`): :data:`FAMILY_FIT_TWO` from both,
    :data:`FAMILY_FIT` from the base alone."""
    designs = (base,) if partner is None else (base, partner)
    results = [solve(d) for d in designs]
    names = FAMILY_FIT if partner is None else FAMILY_FIT_TWO
    cal = calibrate_frame(list(designs), [r[0] for r in results], [r[1] for r in results], names=names)
    errs = tuple(float(np.abs(frame_errors(d, r[0], r[1], cal)).max()) for d, r in zip(designs, results))
    log.info("frame calibrated on %s: %s; max |err| %s", ", ".join(d.name for d in designs),
             ", ".join(f"{n}={getattr(cal, n):.3f}" for n in names), ", ".join(f"{100 * e:.2f} %" for e in errs))
    return FamilyCalibration(cal, names, designs, errs)
