"""The calibration result file (contract ``rodlab.calibration/1``)."""
from __future__ import annotations

from pathlib import Path

from rodlab.fileio import atomic_write_json, json_safe

from .identify import CalibrationResult
from .validate import ErrorStats

__all__ = ["result_dict", "write_result", "FORMAT_CALIBRATION"]

FORMAT_CALIBRATION = "rodlab.calibration/1"


def result_dict(robot, res: CalibrationResult, compensation: str, before: ErrorStats | None = None,
                after: ErrorStats | None = None, extra: dict | None = None) -> dict:
    """Contract calibration result. DH ``d, a, alpha, beta`` are absolute values (nominal + error), ``dtheta``
    the offset error; base / tool / fixture offsets absolute; ``c`` in rad/(N m)."""
    params = {}
    for info in res.infos:
        nm = info.name
        params[nm] = {"value": res.values[nm], "sigma": res.sigma[nm], "unit": info.unit, "status": res.status[nm]}
    out = {"format": FORMAT_CALIBRATION, "robot": robot.name, "compensation": compensation, "trusted": not res.warnings,
           "parameters": params,
           "unidentifiable": res.unidentifiable, "residual_rms_mm": res.rms_mm, "points": int(res.residuals_mm.shape[0]),
           "fit": {"success": res.success, "message": res.message, "nfev": res.nfev,
                   "compensation_passes": res.iterations, "noise_mm": res.noise_mm, "condition": res.condition,
                   "warnings": res.warnings, "cautions": res.cautions}}
    if res.residual_check is not None:
        out["fit"]["residual_test"] = res.residual_check.to_dict()
    if before is not None and after is not None:
        out["validation"] = {"before": before.to_dict(), "after": after.to_dict()}
    if extra:
        out.update(extra)
    return json_safe(out)


def write_result(path: str | Path, data: dict) -> Path:
    return atomic_write_json(path, data)
