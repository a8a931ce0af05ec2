"""Whether to trust a calibration: reasons not to (no convergence, residuals the noise model does not explain by
a material margin, parameters beyond physical bounds) and cautions a trusted result is read with."""
from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from .identify import CalibrationResult

__all__ = ["trust_warnings", "trust_cautions", "ERROR_BOUNDS"]


#: physical bounds of the identified errors; beyond them a result is flagged
ERROR_BOUNDS = {"dtheta": 2.0, "d": 10.0, "a": 10.0, "alpha": 2.0, "beta": 2.0}


def trust_warnings(robot, res: "CalibrationResult") -> list[str]:
    """Reasons not to trust a calibration: no convergence, residuals the noise model does not explain by a
    material margin (Birge ratio above :data:`~calibrate.residual_test.BIRGE_MATERIAL`)
    (:mod:`calibrate.residual_test`, the test ``rodlab diagnose --campaign`` uses too), parameters beyond
    physical bounds."""
    w = []
    if not res.success:
        w.append(f"the Levenberg-Marquardt run did not converge ({res.message})")
    readings = res.residuals_mm.size
    if len(res.free) >= readings:
        w.append(f"{len(res.free)} parameters from {readings} readings leave no degree of freedom to test the fit "
                 "against: measure more points or identify fewer parameters (e.g. fewer --joint-harmonics)")
    test = res.residual_check
    if test is not None and test.material:
        w.append(f"residuals ({res.rms_mm * 1e3:.1f} um rms) are not noise: {test.describe()}; " + (
            "physics is missing: run `rodlab diagnose --campaign` on the same files to find which" if test.clamping
            else "either the instrument is noisier than stated (check --noise-um against its specification) or the "
                 "model misses physics (backlash, non-geometric errors): `rodlab diagnose --points` on the same "
                 "files shows the residuals per joint, workspace region and time"))
    nominal = {"d": robot.d_mm, "a": robot.a_mm, "alpha": robot.alpha_deg, "beta": robot.beta_deg}
    for info in res.infos:
        if res.status[info.name] == "fixed":
            continue
        v = res.values[info.name]
        if info.kind in ERROR_BOUNDS:
            err = v if info.kind == "dtheta" else v - nominal[info.kind][info.index]
            if abs(err) > ERROR_BOUNDS[info.kind]:
                w.append(f"{info.name} moved {err:+.3g} {info.unit} from nominal (bound {ERROR_BOUNDS[info.kind]:g}): "
                         f"not a plausible manufacturing error")
        if info.kind == "c" and not (-1e-6 <= v <= 1e-4):
            w.append(f"{info.name} = {v:.3g} rad/(N m) is outside [0, 1e-4]: not a plausible gearbox compliance")
    return w


def trust_cautions(res: "CalibrationResult") -> list[str]:
    """What a result that passes :func:`trust_warnings` should be read with: residuals significantly but only
    slightly above the noise model (Birge ratio at most :data:`~calibrate.residual_test.BIRGE_MATERIAL`), and
    periodic joint errors identified over part of a turn."""
    return _residual_caution(res) + _partial_turn_cautions(res)


def _partial_turn_cautions(res: "CalibrationResult") -> list[str]:
    return [f"joint {j}'s periodic error was identified over {lo:.0f}..{hi:.0f} deg of its reading: it describes "
            f"the error there, not over the gear's whole turn; do not use it outside that range"
            for j, (lo, hi) in sorted(res.harmonic_range_deg.items()) if hi - lo < 180.0]


def _residual_caution(res: "CalibrationResult") -> list[str]:
    from .residual_test import BIRGE_MATERIAL
    test = res.residual_check
    if test is None or not test.missing or test.material:
        return []
    return [f"residuals are slightly above the noise model: {test.describe()}; the scatter is {test.birge:.2f} "
            f"times the model's (trusted up to {BIRGE_MATERIAL:g}: what is left out moves the points by about the "
            f"noise, and the standard errors above come from the residuals' own scatter); "
            + ("`rodlab diagnose --campaign` looks for a cause" if test.clamping else
               "check --noise-um against the instrument's specification")]
