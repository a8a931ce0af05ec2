"""A calibrated URDF: the robot's own file with its joint origins corrected to the identified model.

Each link keeps its place on the body it belongs to, so meshes and inertials stay where they were. With
``{i}`` the model's frames, ``L_i`` the child link of revolute joint i and ``P_i`` its parent link, the
nominal model ties each link to the axis it turns about by a constant ``Y_i``
(``L_i = T_{i-1} Rz(theta_i) Y_i``) and each parent to the previous link by a constant ``F_i``
(``P_i = L_{i-1} F_i``, the folded fixed joints). The calibrated rows ``M_i = Tz(d_i) Tx(a_i) Rx(alpha_i)
Ry(beta_i)`` and offsets then give the new joint origins exactly:

    origin_i = F_i^-1 Y_{i-1}^-1 M_{i-1} Rz(theta_offset_i) Y_i,    Y_0 = base_T_0^-1, M_0 = I,

and the joint axes stay as written. The measurement frame (the calibrated base pose) and the tool point
become fixed joints: ``rodlab_measurement -> base_link`` and ``tip -> rodlab_tcp``. Joint compliance has no
place in a URDF, nor has a periodic joint error (``rodlab.calibration/2``); the file says so and both go to the
YAML beside it, and the read-back check compares with the model without them.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_text
from rodlab.core.frames import pose_to_matrix

from .errors import CalibrationError
from .kinematics import HARMONICS, ModelParams, ball_positions, forward
from .robot_lines import chain_matrices, row_matrix
from .robot_urdf import UrdfChain, chain_poses, load_urdf, quiet_mesh_names, urdf_chain

__all__ = ["UrdfExport", "calibrated_origins", "write_calibrated_urdf", "MEASUREMENT_LINK", "TCP_LINK", "omitted_mm"]

MEASUREMENT_LINK = "rodlab_measurement"
TCP_LINK = "rodlab_tcp"


@dataclass(frozen=True)
class UrdfExport:
    """A written calibrated URDF: its path, the check of the file read back against the model over the given
    configurations (largest TCP position difference [um]), the new joint origins (name -> 4x4 [mm]), and the
    largest TCP effects [mm] over those configurations of what a URDF cannot hold: (joint compliance under the
    links' own weight, periodic joint errors)."""

    path: Path
    configurations: int
    max_error_um: float
    origins: dict
    omitted_max_mm: tuple = (0.0, 0.0)


def _rz(theta) -> np.ndarray:
    return row_matrix(theta, 0.0, 0.0, 0.0)


def _nominal_ties(robot, ch: UrdfChain) -> tuple[list, list]:
    """``Y_i`` (link on its axis) and ``F_i`` (parent from the previous link) of the nominal model."""
    frames = robot.base_T_0 @ chain_matrices(robot.theta_offset_deg, robot.d_mm, robot.a_mm, robot.alpha_deg,
                                             robot.beta_deg)
    moving = [j for j in ch.joints if j.type != "fixed"]
    Y, F = [np.linalg.inv(robot.base_T_0)], []
    prev_link = ch.base_link
    for i, j in enumerate(moving):
        Y.append(np.linalg.inv(frames[i] @ _rz(np.deg2rad(robot.theta_offset_deg[i]))) @ ch.link_T[j.child])
        F.append(np.linalg.inv(ch.link_T[prev_link]) @ ch.link_T[j.parent])
        prev_link = j.child
    return Y, F


def calibrated_origins(robot, ch: UrdfChain, params: ModelParams) -> tuple[list, np.ndarray, np.ndarray]:
    """New origins of the revolute joints [mm], the base link in the measurement frame, the TCP in the tip."""
    Y, F = _nominal_ties(robot, ch)
    n = robot.n
    M = [np.eye(4)] + [row_matrix(0.0, params.d[i], params.a[i], params.alpha[i], params.beta[i]) for i in range(n)]
    origins = [np.linalg.inv(F[i]) @ np.linalg.inv(Y[i]) @ M[i] @ _rz(params.theta_offset[i]) @ Y[i + 1]
               for i in range(n)]
    last = [j for j in ch.joints if j.type != "fixed"][-1].child
    G = np.linalg.inv(ch.link_T[last]) @ ch.link_T[ch.tip_link]
    tcp = np.eye(4)
    tcp[:3, 3] = (np.linalg.inv(G) @ np.linalg.inv(Y[n]) @ M[n] @ np.r_[params.tool, 1.0])[:3]
    base = pose_to_matrix(params.base) @ np.linalg.inv(robot.base_T_0)
    return origins, base, tcp


def _metres(T) -> np.ndarray:
    out = np.array(T, float)
    out[:3, 3] /= 1000.0
    out[np.abs(out) < 1e-15] = 0.0                      # round-off, not geometry
    return out


def _add_frames(model, ch: UrdfChain, base: np.ndarray, tcp: np.ndarray) -> None:
    """The measurement frame above the base link and the TCP below the tip, as fixed joints."""
    import yourdfpy                                                     # heavy (yourdfpy (trimesh): only for URDF robots)
    model.robot.links += [yourdfpy.Link(name=MEASUREMENT_LINK), yourdfpy.Link(name=TCP_LINK)]
    model.robot.joints += [
        yourdfpy.Joint(name=f"{MEASUREMENT_LINK}-{ch.base_link}", type="fixed", parent=MEASUREMENT_LINK,
                       child=ch.base_link, origin=_metres(base)),
        yourdfpy.Joint(name=f"{ch.tip_link}-{TCP_LINK}", type="fixed", parent=ch.tip_link, child=TCP_LINK,
                       origin=_metres(tcp))]


def _note(robot, params: ModelParams, source: str) -> str:
    c = ", ".join(f"{nm}: {v:.4g}" for nm, v in zip(robot.joint_names, params.c))
    text = ("<!-- Calibrated by rodlab from " + source + ": joint origins corrected to the identified model; "
            f"{MEASUREMENT_LINK} is the measurement frame (calibrated base pose), {TCP_LINK} the calibrated tool "
            "point. Joint compliance cannot be expressed in URDF and is NOT in this file: theta_i = q_i + c_i tau_i "
            f"with c [rad/(N m)] = {{{c}}} (also in the YAML written beside this file).")
    if params.h.any():
        terms = " + ".join(f"{t} {'sin' if f is np.sin else 'cos'}({k if k > 1 else ''}q_i)"
                           for t, (k, f) in HARMONICS.items())
        h = "; ".join(f"{nm}: " + ", ".join(f"{t} {v:.4g}" for t, v in zip(HARMONICS, np.rad2deg(row)))
                      for nm, row in zip(robot.joint_names, params.h) if row.any())
        text += (" Nor can the periodic joint errors, which are NOT in this file either: the joint turns by its "
                 f"reading plus {terms} [deg], each term less its mean over the calibration's readings (the YAML "
                 f"gives the terms, those means and the range of readings they hold for), with {h}; a controller "
                 "commanding an angle subtracts it.")
    return text + " -->"


def write_calibrated_urdf(urdf_path, robot, params: ModelParams, out_path, q_check_rad, base_link=None,
                          tip_link=None, source: str = "a calibration") -> UrdfExport:
    """Write the corrected URDF atomically, read it back and check its TCP against the model (c = 0, h = 0)."""
    model = load_urdf(urdf_path)
    ch = urdf_chain(model, base_link, tip_link, path=urdf_path)
    if ch.revolute != tuple(robot.joint_names):
        raise CalibrationError(f"the URDF's chain {list(ch.revolute)} is not the robot's {list(robot.joint_names)}",
                               path=urdf_path)
    names = {lk.name for lk in model.robot.links}
    for taken in (MEASUREMENT_LINK, TCP_LINK):
        if taken in names:
            raise CalibrationError(f"already has a link {taken!r}: export from the original URDF, not a calibrated "
                                   "one", path=urdf_path)
    origins, base, tcp = calibrated_origins(robot, ch, params)
    by_name = {j.name: j for j in model.robot.joints}
    for name, T in zip(ch.revolute, origins):
        by_name[name].origin = _metres(T)
    _add_frames(model, ch, base, tcp)
    from lxml import etree                              # yourdfpy's own XML library
    with quiet_mesh_names():
        text = etree.tostring(model.write_xml(), pretty_print=True, encoding="unicode")
    text = '<?xml version="1.0" encoding="utf-8"?>\n' + _note(robot, params, source) + "\n" + text
    out = Path(out_path)
    err = _check(text, out, params, q_check_rad)
    atomic_write_text(out, text)
    return UrdfExport(out, int(np.atleast_2d(q_check_rad).shape[0]), err, dict(zip(ch.revolute, origins)),
                      omitted_mm(robot, params, q_check_rad))


def omitted_mm(robot, params: ModelParams, q) -> tuple[float, float]:
    """Largest TCP effect [mm] over the configurations ``q`` (k, n) [rad] of the joint compliance (no payload) and of
    the periodic joint errors: what the model's geometric part (a URDF, a DH table) leaves out."""
    q = np.atleast_2d(q)
    no_h = params.with_(h=np.zeros_like(params.h))
    compliance = ball_positions(robot, no_h, q)[0].pW - forward(no_h, q).pW
    periodic = forward(params, q).pW - forward(no_h, q).pW
    return tuple(float(np.linalg.norm(d, axis=1).max()) for d in (compliance, periodic))


def _check(text: str, out: Path, params: ModelParams, q) -> float:
    """Largest TCP difference [um] of the text, parsed as the written file will be, from the model."""
    tmp = out.with_name(f".{out.name}.check.urdf")
    try:
        tmp.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(text, encoding="utf-8")
        ch = urdf_chain(load_urdf(tmp), MEASUREMENT_LINK, TCP_LINK, path=out)
    finally:
        tmp.unlink(missing_ok=True)
    urdf_tcp = chain_poses(ch, q)[:, :3, 3]
    model_tcp = forward(params.with_(c=np.zeros_like(params.c), h=np.zeros_like(params.h)), np.atleast_2d(q)).pW
    err = float(np.abs(urdf_tcp - model_tcp).max() * 1000.0)
    if not err <= 1.0:
        raise CalibrationError(f"the calibrated URDF read back differs from the model by {err:.3g} um (> 1 um); "
                               "nothing written. Please report this with the files.", path=out)
    return err
