"""The calibration result file (contract ``rodlab.calibration/1``; ``/2`` when it carries periodic joint errors)."""
from __future__ import annotations

from pathlib import Path

from rodlab.fileio import atomic_write_json, json_safe

from .identify import CalibrationResult
from .kinematics import HARMONICS
from .validate import ErrorStats

__all__ = ["result_dict", "write_result", "FORMAT_CALIBRATION", "FORMAT_CALIBRATION_HARMONICS", "CALIBRATION_FORMATS"]

FORMAT_CALIBRATION = "rodlab.calibration/1"
#: the same with the periodic joint-error parameters ``h1s_j .. h2c_j``: a new version, so that a reader of
#: ``/1`` refuses the file instead of dropping a part of the model it does not know
FORMAT_CALIBRATION_HARMONICS = "rodlab.calibration/2"
CALIBRATION_FORMATS = (FORMAT_CALIBRATION, FORMAT_CALIBRATION_HARMONICS)


def result_dict(robot, res: CalibrationResult, compensation: str, before: ErrorStats | None = None,
                after: ErrorStats | None = None, extra: dict | None = None) -> dict:
    """Contract calibration result. DH ``d, a, alpha, beta`` are absolute values (nominal + error), ``dtheta``
    the offset error; base / tool / fixture offsets absolute; ``c`` in rad/(N m); periodic joint errors in deg."""
    params = {}
    for info in res.infos:
        nm = info.name
        params[nm] = {"value": res.values[nm], "sigma": res.sigma[nm], "unit": info.unit, "status": res.status[nm]}
    harmonic = any(info.kind in HARMONICS for info in res.infos)
    out = {"format": FORMAT_CALIBRATION_HARMONICS if harmonic else FORMAT_CALIBRATION, "robot": robot.name,
           "compensation": compensation, "trusted": not res.warnings,
           "parameters": params,
           "unidentifiable": res.unidentifiable, "residual_rms_mm": res.rms_mm, "points": int(res.residuals_mm.shape[0]),
           "fit": {"success": res.success, "message": res.message, "nfev": res.nfev,
                   "compensation_passes": res.iterations, "noise_mm": res.noise_mm, "condition": res.condition,
                   "warnings": res.warnings, "cautions": res.cautions}}
    if res.residual_check is not None:
        out["fit"]["residual_test"] = res.residual_check.to_dict()
        from .trust import completeness, completeness_statement
        out["fit"]["completeness"] = {"verdict": str(completeness(res)), "statement": completeness_statement(res)}
    if res.prediction is not None:
        out["fit"]["prediction"] = res.prediction.to_dict()
    if harmonic:
        out["joint_harmonics"] = {str(j): {"reference": res.params.h_ref[j - 1].tolist(), "q_min_deg": lo,
                                           "q_max_deg": hi} for j, (lo, hi) in res.harmonic_range_deg.items()}
    if before is not None and after is not None:
        out["validation"] = {"before": before.to_dict(), "after": after.to_dict()}
    if extra:
        out.update(extra)
    return json_safe(out)


def write_result(path: str | Path, data: dict) -> Path:
    return atomic_write_json(path, data)
