"""Calibrated parameters for controllers and ROS: a YAML of values with 1-sigma, and the DH table as CSV.

The YAML follows the idea of ROS calibration packages' files (``ur_calibration``'s ``kinematics:`` block of
joint origins as ``x, y, z, roll, pitch, yaw`` in metres and radians, here one entry per URDF joint name, not
its DH segments), with rodlab's own
identified parameters (value, sigma, unit, status) and the joint compliances, which no URDF can carry. The CSV
is one row per joint of the model's table (``T = Rz(theta) Tz(d) Tx(a) Rx(alpha) Ry(beta)``) with nominal,
calibrated and sigma columns, for controllers that take a DH table.
"""
from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_text

from .result import CalibrationFile, joint_zero_shifts_deg
from .kinematics import HARMONICS, ModelParams

__all__ = ["params_yaml", "dh_table_csv", "write_params_yaml", "write_dh_csv"]

_ROW = (("theta_offset", "deg"), ("d", "mm"), ("a", "mm"), ("alpha", "deg"), ("beta", "deg"), ("c", "rad/(N m)"))


def _rpy(R) -> tuple[float, float, float]:
    """URDF roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll))."""
    pitch = float(np.arcsin(np.clip(-R[2, 0], -1.0, 1.0)))
    if abs(np.cos(pitch)) < 1e-9:
        return float(np.arctan2(-R[1, 2], R[1, 1])), pitch, 0.0
    return float(np.arctan2(R[2, 1], R[2, 2])), pitch, float(np.arctan2(R[1, 0], R[0, 0]))


def _num(v: float) -> str:
    v = float(v)
    return (repr(v) if abs(v) > 1e-15 else "0.0") if np.isfinite(v) else ".nan"


def params_yaml(robot, cal: CalibrationFile, params: ModelParams, origins: dict | None = None) -> str:
    """The YAML text; ``origins`` (joint name -> 4x4 [mm]) adds the ``kinematics`` block of a URDF export."""
    out = io.StringIO()
    out.write(f"# Calibrated parameters of {robot.name} written by `rodlab export` from {cal.path.name}\n"
              f"# (compensation {cal.compensation or 'none'}, trusted: {str(cal.trusted).lower()}, residual rms "
              f"{cal.residual_rms_mm:.4g} mm). Values in the units given; sigma is 1 standard deviation.\n")
    out.write(f"robot: {robot.name}\nsource: {cal.path.name}\ntrusted: {str(cal.trusted).lower()}\n")
    if origins:
        out.write("kinematics:   # URDF joint origins (parent link -> joint frame), metres and radians\n")
        for name, T in origins.items():
            r, p, y = _rpy(T[:3, :3])
            x, yy, z = T[:3, 3] / 1000.0
            out.write(f"  {name}: {{x: {_num(x)}, y: {_num(yy)}, z: {_num(z)}, roll: {_num(r)}, pitch: {_num(p)}, "
                      f"yaw: {_num(y)}}}\n")
    out.write("joint_compliance:   # theta_i = q_i + c_i tau_i; not expressible in URDF\n")
    for i, name in enumerate(robot.joint_names):
        sp = cal.parameters.get(f"c_{i + 1}")
        out.write(f"  {name}: {{value: {_num(params.c[i])}, sigma: {_num(sp.sigma if sp else 0.0)}, "
                  f"unit: rad/(N m)}}\n")
    if params.h.any():
        _harmonics_yaml(out, robot, cal, params)
    out.write("parameters:   # every parameter of the identification\n")
    twist = f"dtheta_{robot.n}"
    shift = joint_zero_shifts_deg(robot, cal)
    for name, v in cal.parameters.items():
        note = "   # with the rod's mounting twist about the flange axis (one rod cannot separate them)" \
            if name == twist else ""
        value = v.value
        kind, _, j = name.rpartition("_")
        if kind == "dtheta" and j.isdigit() and shift[int(j) - 1]:     # to this description's zero of the joint
            value = v.value + shift[int(j) - 1]
            note = (f"   # re-referenced to this description's zero ({_num(v.value)} identified against the "
                    f"calibration's, {_num(cal.description['theta_offset_deg'][int(j) - 1])} deg)") + note
        out.write(f"  {name}: {{value: {_num(value)}, sigma: {_num(v.sigma)}, unit: {v.unit}, status: {v.status}}}"
                  f"{note}\n")
    return out.getvalue()


def _harmonics_yaml(out, robot, cal: CalibrationFile, params: ModelParams) -> None:
    """``joint_harmonics:``: per joint its four terms with sigma, their references and the readings' range."""
    out.write("joint_harmonics:   # theta_i = q_i + sum_k h_k (f_k(q_i) - reference_k), f = sin q, cos q, sin 2q, cos 2q; "
              "h in deg, reference (the means of f) unitless; valid over q_min..q_max; not expressible in URDF\n")
    for i, name in enumerate(robot.joint_names):
        if not params.h[i].any():
            continue
        terms = ", ".join(f"{t}: {{value: {_num(v)}, sigma: {_num(cal.parameters[f'{t}_{i + 1}'].sigma)}}}"
                          for t, v in zip(HARMONICS, np.rad2deg(params.h[i])) if f"{t}_{i + 1}" in cal.parameters)
        lo, hi = cal.harmonic_range_deg.get(i + 1, (float("nan"), float("nan")))
        ref = ", ".join(_num(v) for v in params.h_ref[i])
        out.write(f"  {name}: {{{terms}, unit: deg, reference: [{ref}], q_min_deg: {_num(lo)}, "
                  f"q_max_deg: {_num(hi)}}}\n")


def _nominal_row(robot, i: int) -> dict:
    return {"theta_offset": robot.theta_offset_deg[i], "d": robot.d_mm[i], "a": robot.a_mm[i],
            "alpha": robot.alpha_deg[i], "beta": robot.beta_deg[i], "c": 0.0}


def _calibrated_row(params: ModelParams, i: int) -> dict:
    theta = (np.rad2deg(params.theta_offset[i]) + 180.0) % 360.0 - 180.0       # within +-180 deg
    return {"theta_offset": theta, "d": params.d[i], "a": params.a[i],
            "alpha": np.rad2deg(params.alpha[i]), "beta": np.rad2deg(params.beta[i]), "c": params.c[i]}


def dh_table_csv(robot, cal: CalibrationFile, params: ModelParams) -> str:
    """One row per joint: nominal, calibrated and sigma of each DH quantity (and the compliance c)."""
    cols = ["joint", "name"] + [f"{k}_{what}" for k, _ in _ROW for what in ("nominal", "calibrated", "sigma")]
    left_out = ("; the periodic joint errors of " + ", ".join(n for n, h in zip(robot.joint_names, params.h) if h.any())
                + " are not in this table (see the YAML)") if params.h.any() else ""
    lines = [f"# {robot.name}: T_(i-1,i) = Rz(theta_offset_i + q_i) Tz(d_i) Tx(a_i) Rx(alpha_i) Ry(beta_i); units: "
             + ", ".join(f"{k} [{u}]" for k, u in _ROW) + f"; from {cal.path.name}{left_out}", ",".join(cols)]
    for i, name in enumerate(robot.joint_names):
        nom, now = _nominal_row(robot, i), _calibrated_row(params, i)
        cells = [str(i + 1), name]
        for k, _ in _ROW:
            key = "dtheta" if k == "theta_offset" else k
            sp = cal.parameters.get(f"{key}_{i + 1}")
            cells += [f"{nom[k]:.9g}", f"{now[k]:.9g}", f"{sp.sigma if sp else 0.0:.3g}"]
        lines.append(",".join(cells))
    return "\n".join(lines) + "\n"


def write_params_yaml(path, robot, cal, params, origins=None) -> Path:
    return atomic_write_text(path, params_yaml(robot, cal, params, origins))


def write_dh_csv(path, robot, cal, params) -> Path:
    return atomic_write_text(path, dh_table_csv(robot, cal, params))
