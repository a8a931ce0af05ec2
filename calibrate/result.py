"""The calibration result: the type identification returns (:class:`CalibrationResult`), its file (contract
``rodlab.calibration/1``; ``/2`` when it carries periodic joint errors) written (:func:`result_dict`,
:func:`write_result`) and read back (:func:`read_calibration`) with the model it describes
(:func:`calibrated_params`)."""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from rodlab.core.fileio import atomic_write_json, json_safe
from rodlab.core.schema import require_schema

from .errors import CalibrationError
from .kinematics import HARMONICS, ModelParams
from .trust import completeness, completeness_statement

if TYPE_CHECKING:                                      # validate -> points -> identify -> result
    from .validate import ErrorStats

__all__ = ["CalibrationResult", "result_dict", "write_result", "FORMAT_CALIBRATION", "FORMAT_CALIBRATION_HARMONICS",
           "CALIBRATION_FORMATS", "CalibratedParameter", "CalibrationFile", "read_calibration", "calibrated_params",
           "description_notes", "joint_zero_shifts_deg", "description_of"]

FORMAT_CALIBRATION = "rodlab.calibration/1"
#: the same with the periodic joint-error parameters ``h1s_j .. h2c_j``: a new version, so that a reader of
#: ``/1`` refuses the file instead of dropping a part of the model it does not know
FORMAT_CALIBRATION_HARMONICS = "rodlab.calibration/2"
CALIBRATION_FORMATS = (FORMAT_CALIBRATION, FORMAT_CALIBRATION_HARMONICS)


@dataclass
class CalibrationResult:
    """Identified model and its statistics (scipy ``OptimizeResult`` style).

    params : the identified :class:`ModelParams`; values / sigma : {name: value in contract units};
    status : {name: identified | fixed | regularised}; unidentifiable : reasons; residuals_mm : (N, 3);
    rms_mm : per scalar reading; noise_mm : estimate; correlation : (P, P) of the free parameters;
    offsets_W_mm : the compensated rod-deflection offsets (N, 3); success, message, nfev, iterations;
    warnings : reasons not to trust the result (:func:`trust_warnings`); cautions : what a trusted result
    should still be read with (:func:`trust_cautions`); residual_check : the residual test, or None;
    harmonic_range_deg : {joint: (min, max) [deg]}: the readings the periodic terms were identified over;
    prediction : the held-out accuracy (:class:`~calibrate.crossval.Prediction`) once the caller has judged it
    (:func:`~calibrate.trust.prediction_warnings`), else None; unconstrained : {name: value [rad/(N m)]} of each
    joint compliance held at its lower bound 0, where one step from the fit without the bound puts it
    """

    params: ModelParams
    infos: list
    values: dict
    sigma: dict
    status: dict
    unidentifiable: list
    residuals_mm: np.ndarray
    rms_mm: float
    noise_mm: float
    correlation: np.ndarray
    free: list
    offsets_W_mm: np.ndarray
    success: bool
    message: str
    nfev: int = 0
    iterations: int = 0
    condition: float = float("nan")
    warnings: list = field(default_factory=list)
    residual_check: object = None          # calibrate.residual_test.ResidualTest, or None without a noise level
    cautions: list = field(default_factory=list)
    harmonic_range_deg: dict = field(default_factory=dict)   # joint (1-based) -> (min, max) reading [deg] of the data
    prediction: object = None              # calibrate.crossval.Prediction (held-out accuracy), or None
    unconstrained: dict = field(default_factory=dict)   # joint compliance held at 0 -> where the data put it


#: the robot description's nominal rows a result records (``description``): the ``dtheta`` are relative to its
#: ``theta_offset_deg``, so a result applied to a description with other joint zeros is another robot
DESCRIPTION_ROWS = ("theta_offset_deg", "d_mm", "a_mm", "alpha_deg", "beta_deg")


def description_of(robot) -> dict:
    """The description's nominal DH rows [deg, mm] a calibration of ``robot`` is made against."""
    return {k: [float(v) for v in getattr(robot, k)] for k in DESCRIPTION_ROWS}


def result_dict(robot, res: CalibrationResult, compensation: str, before: ErrorStats | None = None,
                after: ErrorStats | None = None, extra: dict | None = None) -> dict:
    """Contract calibration result. DH ``d, a, alpha, beta`` are absolute values (nominal + error), ``dtheta``
    the offset error; base / tool / fixture offsets absolute; ``c`` in rad/(N m); periodic joint errors in deg."""
    params = {}
    for info in res.infos:
        nm = info.name
        params[nm] = {"value": res.values[nm], "sigma": res.sigma[nm], "unit": info.unit, "status": res.status[nm]}
        if nm in res.unconstrained:                 # held at 0: where the data, unbounded, put it
            params[nm]["at_bound"] = True
            params[nm]["unconstrained_value"] = res.unconstrained[nm]
    harmonic = any(info.kind in HARMONICS for info in res.infos)
    out = {"format": FORMAT_CALIBRATION_HARMONICS if harmonic else FORMAT_CALIBRATION, "robot": robot.name,
           "compensation": compensation, "trusted": not res.warnings,
           "parameters": params, "description": description_of(robot),
           "unidentifiable": res.unidentifiable, "residual_rms_mm": res.rms_mm, "points": int(res.residuals_mm.shape[0]),
           "fit": {"success": res.success, "message": res.message, "nfev": res.nfev,
                   "compensation_passes": res.iterations, "noise_mm": res.noise_mm, "condition": res.condition,
                   "warnings": res.warnings, "cautions": res.cautions,
                   "correlation": {"names": list(res.free), "matrix": np.asarray(res.correlation).tolist()}}}
    if res.residual_check is not None:
        out["fit"]["residual_test"] = res.residual_check.to_dict()
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


@dataclass(frozen=True)
class CalibratedParameter:
    """One parameter of a result: value and 1-sigma in ``unit`` (contract units), and how it was treated
    (``identified`` / ``regularised`` / ``fixed`` / ``pinned``)."""

    value: float
    sigma: float
    unit: str
    status: str


@dataclass(frozen=True)
class CalibrationFile:
    """A calibration result: the robot's name, the compensation, whether it is trusted, the parameters; for a
    ``/2`` result the periodic terms' references (joint -> 4 means) and the readings they were identified over
    (joint -> (min, max) [deg]); the correlation matrix of the free parameters (``fit.correlation``: names, and
    shape=(P, P)), or None in a file written before it was recorded; the robot ``description``'s nominal rows the
    calibration was made against ({row: (n,) list}, :data:`DESCRIPTION_ROWS`), or None in a file written before it
    was recorded."""

    path: Path
    robot: str
    compensation: str
    trusted: bool
    residual_rms_mm: float
    parameters: dict
    harmonic_reference: dict = field(default_factory=dict)
    harmonic_range_deg: dict = field(default_factory=dict)
    correlation_names: tuple = ()
    correlation: np.ndarray | None = None
    description: dict | None = None


def read_calibration(path) -> CalibrationFile:
    """Read a result file; errors name the file and key and say what is expected."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
        data = json.loads(text)
    except FileNotFoundError as e:
        raise CalibrationError("file not found", path=p) from e
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        line = getattr(e, "lineno", None)
        raise CalibrationError(f"not a JSON calibration result: {e}", path=p, line=line) from e
    if not isinstance(data, dict) or data.get("format") not in CALIBRATION_FORMATS:
        got = data.get("format") if isinstance(data, dict) else type(data).__name__
        raise CalibrationError(f"expected format \"{FORMAT_CALIBRATION}\" or \"{CALIBRATION_FORMATS[1]}\" (written by "
                               f"`rodlab calibrate --json`), got {got!r}", path=p, key="format")
    require_schema(data, FORMAT_CALIBRATION, p, text, CalibrationError)   # every parameter {value, unit, ...}
    params = {name: CalibratedParameter(float(v["value"]), _sigma(v), str(v["unit"]), str(v.get("status", "")))
              for name, v in data["parameters"].items()}
    ref, rng = _harmonics(data, params, p)
    names, corr = _correlation(data, params, p)
    return CalibrationFile(p, str(data.get("robot", "")), str(data.get("compensation", "")),
                           bool(data.get("trusted", False)), float(data.get("residual_rms_mm", float("nan"))), params,
                           ref, rng, names, corr, _description(data, p))


def _description(data: dict, p: Path) -> dict | None:
    """``description``: every row of :data:`DESCRIPTION_ROWS`, as many finite numbers each; None when absent."""
    block = data.get("description")
    if block is None:
        return None
    try:
        rows = {k: [float(v) for v in block[k]] for k in DESCRIPTION_ROWS}
    except (KeyError, TypeError, ValueError) as e:
        raise CalibrationError(f"description: expected {{{', '.join(DESCRIPTION_ROWS)}: [one number per joint]}} "
                               f"({e})", path=p, key="description") from e
    if len({len(v) for v in rows.values()}) != 1 or not all(np.isfinite(v).all() for v in rows.values()):
        raise CalibrationError("description: expected as many finite numbers in every row", path=p, key="description")
    return rows


def _correlation(data: dict, params: dict, p: Path) -> tuple[tuple, np.ndarray | None]:
    """``fit.correlation``: (names, shape=(P, P) matrix), or ((), None) where the file has none."""
    block = (data.get("fit") or {}).get("correlation")
    if block is None:
        return (), None
    try:
        names = tuple(str(n) for n in block["names"])
        matrix = np.array([[np.nan if v is None else v for v in row] for row in block["matrix"]], float)
    except (KeyError, TypeError, ValueError) as e:
        raise CalibrationError(f"fit.correlation: expected {{\"names\": [...], \"matrix\": [[...]]}} ({e})", path=p,
                               key="fit.correlation") from e
    unknown = [n for n in names if n not in params]
    if matrix.shape != (len(names), len(names)) or unknown:                # null (NaN): a direction the data do not see
        raise CalibrationError(f"fit.correlation: expected a {len(names)} x {len(names)} matrix over parameters of "
                               f"the file, got shape {matrix.shape}" + (f" and unknown names {unknown}" if unknown else ""),
                               path=p, key="fit.correlation")
    return names, matrix


def _harmonics(data: dict, params: dict, p: Path) -> tuple[dict, dict]:
    """The ``/2`` block: {joint: reference} and {joint: (min, max)}; periodic parameters need it and ``/2``."""
    named = [name.rpartition("_") for name in params if name.rpartition("_")[0] in HARMONICS]
    bad = [f"{k}_{j}" for k, _, j in named if not j.isdigit()]
    if bad:
        raise CalibrationError(f"parameters {bad}: a periodic joint error is named like h1s_4 (term, joint number)",
                               path=p, key="parameters")
    joints = {int(j) for _, _, j in named}
    block = data.get("joint_harmonics", {})
    reversed_ = [j for j, v in block.items() if v["q_min_deg"] > v["q_max_deg"]]
    if reversed_:
        raise CalibrationError(f"joint_harmonics of joints {reversed_}: q_min_deg is above q_max_deg", path=p,
                               key="joint_harmonics")
    if (joints or block) and data["format"] == FORMAT_CALIBRATION:
        raise CalibrationError(f"periodic joint-error parameters of joints {sorted(joints)} in a \"{FORMAT_CALIBRATION}\" "
                               f"file: they belong to \"{CALIBRATION_FORMATS[1]}\" (written by `rodlab calibrate "
                               f"--joint-harmonics`)", path=p, key="format")
    missing = sorted(j for j in joints if str(j) not in block)
    if missing:
        raise CalibrationError(f"periodic joint errors of joints {missing} have no reference in `joint_harmonics`; "
                               f"write the file with `rodlab calibrate --joint-harmonics`", path=p,
                               key="joint_harmonics")
    return ({int(j): v["reference"] for j, v in block.items()},
            {int(j): (v["q_min_deg"], v["q_max_deg"]) for j, v in block.items()})


def _sigma(v: dict) -> float:
    """A parameter's standard error: absent (a held parameter) is 0; ``null`` is what JSON makes of an infinite
    one (a direction the data do not see), read back as ``inf``."""
    if "sigma" not in v:
        return 0.0
    return float("inf") if v["sigma"] is None else float(v["sigma"])


def calibrated_params(robot, cal: CalibrationFile) -> ModelParams:
    """The identified model (internal units) of ``robot``; parameters absent from the file stay nominal; the joint
    offsets re-referenced to ``robot``'s joint zeros where the result records others (:func:`joint_zero_shifts_deg`)."""
    n = robot.n
    joints = {int(k.split("_")[1]) for k in cal.parameters if k.startswith("dtheta_") and k[7:].isdigit()}
    if joints != set(range(1, n + 1)):
        raise CalibrationError(f"this result does not describe a {n}-joint robot (robot {robot.name!r}); export "
                               f"with the robot the calibration used (it says {cal.robot!r})", path=cal.path,
                               key="parameters")
    _check_description(robot, cal)
    beyond = sorted(j for j in cal.harmonic_reference if not 1 <= j <= n)   # every term's joint has one (read_calibration)
    if beyond:
        raise CalibrationError(f"periodic joint errors of joints {beyond}, which this {n}-joint robot does not have; "
                               f"export with the robot the calibration used (it says {cal.robot!r})", path=cal.path,
                               key="joint_harmonics")
    p = ModelParams.nominal(robot, np.zeros(3))

    def get(name, default):
        return cal.parameters[name].value if name in cal.parameters else default

    rows = {k: np.array([get(f"{k}_{i + 1}", float(v[i])) for i in range(n)])
            for k, v in (("d", robot.d_mm), ("a", robot.a_mm), ("alpha", robot.alpha_deg), ("beta", robot.beta_deg),
                         ("dtheta", np.zeros(n)), ("c", np.zeros(n)))}
    rows["dtheta"] = rows["dtheta"] + joint_zero_shifts_deg(robot, cal)     # relative to the calibration's zeros
    h = np.deg2rad([[get(f"{t}_{i + 1}", 0.0) for t in HARMONICS] for i in range(n)])
    h_ref = np.array([cal.harmonic_reference.get(i + 1, [0.0] * len(HARMONICS)) for i in range(n)], float)
    return ModelParams(np.deg2rad(robot.theta_offset_deg + rows["dtheta"]), rows["d"], rows["a"],
                       np.deg2rad(rows["alpha"]), np.deg2rad(rows["beta"]), rows["c"],
                       np.array([get(f"base_{k}", 0.0) for k in "xyzabc"]),
                       np.array([get(f"tool_{k}", float(p.tool[i])) for i, k in enumerate("xyz")]), h, h_ref)


def joint_zero_shifts_deg(robot, cal: CalibrationFile) -> np.ndarray:
    """(n,) [deg] the joint zeros the calibration recorded (``description.theta_offset_deg``) minus ``robot``'s,
    wrapped to +-180: what re-references its ``dtheta`` to this description; zeros for a result that does not record
    them. Raises :class:`CalibrationError` for a description of another number of joints."""
    ours = np.asarray(robot.theta_offset_deg, float)
    if cal.description is None:
        return np.zeros_like(ours)
    theirs = np.asarray(cal.description["theta_offset_deg"], float)
    if theirs.shape != ours.shape:
        raise CalibrationError(f"the calibration was made against a {theirs.size}-joint description, this robot "
                               f"({robot.name!r}) has {ours.size} joints: export with the one the calibration used (it "
                               f"names {cal.robot!r})", path=cal.path, key="description")
    shift = (theirs - ours + 180.0) % 360.0 - 180.0
    return np.where(np.abs(shift) > 1e-9, shift, 0.0)


def description_notes(robot, cal: CalibrationFile) -> list[str]:
    """What to tell a user who applies ``cal`` to ``robot``: a result that does not record its description (it
    cannot be checked), joints this description counts from other zeros (their offsets re-referenced)."""
    if cal.description is None:
        return [f"warning: {cal.path.name} does not record the robot description it was calibrated against (written "
                "before rodlab recorded it): make sure this robot file is that description, joint zeros included; "
                "calibrate again to have it checked"]
    shift = joint_zero_shifts_deg(robot, cal)
    moved = np.nonzero(shift)[0]
    if not moved.size:
        return []
    theirs = cal.description["theta_offset_deg"]
    rows = "; ".join(f"joint {j + 1}: {round(theirs[j], 6) + 0.0:g} deg there, "
                     f"{round(float(robot.theta_offset_deg[j]), 6) + 0.0:g} deg here" for j in moved)
    return [f"note: this robot description ({robot.name!r}) counts joints from other zeros than the one the calibration "
            f"used ({rows}): their identified offsets are re-referenced to this description's zeros, so the model "
            "written is the calibrated one (the YAML's dtheta too, each with the identified value in a comment)"]


def _check_description(robot, cal: CalibrationFile) -> None:
    """Rows the calibration held at nominal must be this description's nominal: else it is another robot file (a
    URDF's rows differ from a hand-written DH table of the same arm). Joint zeros are re-referenced instead
    (:func:`joint_zero_shifts_deg`: a trial's URDF with an elbow zero 2.9 deg off had been exported 6.8 mm wrong with
    a passing read-back)."""
    nominal = {"d": robot.d_mm, "a": robot.a_mm, "alpha": robot.alpha_deg, "beta": robot.beta_deg}
    for name, v in cal.parameters.items():
        kind, _, idx = name.rpartition("_")
        if v.status != "fixed" or kind not in nominal or not idx.isdigit():
            continue
        expected = float(nominal[kind][int(idx) - 1])
        if abs(v.value - expected) > 1e-6 * max(1.0, abs(expected)):
            raise CalibrationError(f"{name} was held at {v.value:g} {v.unit} by the calibration, but this robot "
                                   f"description ({robot.name!r}) has {expected:g}: the result was made with another "
                                   f"description of the robot (it names {cal.robot!r}); export with the one the "
                                   f"calibration used", path=cal.path,
                                   key=f"parameters.{name}")
