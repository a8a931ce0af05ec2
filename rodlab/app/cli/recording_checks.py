"""What a rig recording must pass before it is diagnosed (``rodlab diagnose --rig``, ``rodlab update --measured
X.rig.csv``): the problems of the instruments and units that the diagnosis would otherwise read as the rod's physics."""
from __future__ import annotations

import sys

from rodlab.stiffness_rig import NoLoadResponse, RigError, fit_recording
from rodlab.stiffness_rig.fit import r_rod_caution
from rodlab.stiffness_rig.fit_checks import gauge_scale_problems, load_scale_problems, reciprocity_problems

__all__ = ["check_recording"]


def check_recording(rec, sim, units_checked: bool = False, override: str | None = "--units-checked") -> None:
    """A recording without a load response is refused with its cause, and so is an r_rod no rod of this kind has
    against its own simulation (a units slip or another rod's file: the diagnosis would fit a compliance scale of
    0.001 and call the recording explained) or one gauge reading a units factor off the others against the
    simulation (a gauge in inches: diagnosed as a compliance scale of 0.26 and a non-linearity along x) or a load
    cell whose readings do not grow as the hung weight (:func:`~stiffness_rig.fit_checks.load_scale_problems`) or a
    gauge reversed in one series (:func:`~stiffness_rig.fit_checks.reciprocity_problems`: diagnosed as a crosstalk
    at its bound, a tilted load line and a joint, a technician trial); ``units_checked`` warns instead (the
    command's option ``override``, None where it has none); any other fit problem is left to the diagnosis."""
    try:
        fit = fit_recording(rec, sim)
    except NoLoadResponse:
        raise
    except RigError:
        return
    # a load cell in another unit, wired the other way or out of the load path: the diagnosis would name a
    # compliance scale of that factor (a cell in lbf: r = 4.33, "decisive"); first, as it explains an r_rod of
    # that factor (a cell 1000 x low had been blamed on the masses and the gauges)
    caution = "; ".join(load_scale_problems(fit.load)[0]) or None
    caution = caution or (r_rod_caution(fit.r_rod, rec.rod, sim.rod) if fit.r_rod is not None else None)
    caution = caution or "; ".join(gauge_scale_problems(fit.C_F_meas, sim.C_F)) or None
    caution = caution or "; ".join(reciprocity_problems(fit.C_F_meas, fit.C_F_se)[0]) or None
    if caution and not units_checked:
        lift = f" (if the files are right, give {override})" if override else ""
        raise RigError(f"{caution}; nothing was diagnosed{lift}", path=rec.path)
    if caution:
        print(f"warning: {caution} ({override}: diagnosed as they are)", file=sys.stderr)
