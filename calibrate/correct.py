"""A calibration made usable by a controller that keeps its nominal model (and its analytic IK): for TCP position
targets (:func:`correct_targets`) or poses where the tool defines the orientation (:func:`correct_poses`), the
joint commands that put the calibrated robot on each target, and the corrected targets to give the nominal
controller instead; and where the calibrated geometry breaks an analytic-IK assumption of the nominal one
(:func:`ik_assumptions`: parallel or intersecting axes that are no longer exactly so).

Targets are positions of the TCP (the calibration's tool point, or another point on the flange) in the frame
the calibration measured in ({W}), for poses with the tool frame's orientation there; both models carry the
calibrated base there, so the nominal controller is assumed registered to that frame (its user frame), as a
cell calibration does. Position targets: the project's batched position IK (:mod:`calibrate.ik`), first the
nominal model's solution near the program's configuration (the seed), then the calibrated model's from there
(pulled towards it: a position leaves a 6-joint arm three redundant degrees of freedom, so the tool's
orientation is not a target and stays near the nominal solution's). Pose targets: the same two steps with the
6-D IK of :mod:`calibrate.ik_pose`. The corrected target is the nominal model's TCP pose at the commands
(position and the flange's, or the tool frame's, orientation): a controller's pose IK of it returns the commands.
"""
from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np

from rodlab.core.frames import matrix_to_pose, pose_to_matrix

from .errors import CalibrationError
from .ik import solve_ik_positions
from .ik_pose import rotation_angle, solve_ik_poses, tcp_poses
from .kinematics import ModelParams, ball_positions

__all__ = ["Correction", "correct_targets", "correct_poses", "AxisDeviation", "ik_assumptions", "CONFIGURATION_JUMP_RAD"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Correction:
    """Joint commands and corrected targets for M TCP targets.

    q_rad : shape=(M, n) joint commands [rad] that put the calibrated robot's TCP on the target;
    corrected_mm : shape=(M, 3) the target to give a controller that uses the nominal model [mm] in {W}: the
    nominal model's TCP at those commands; corrected_abc_deg : shape=(M, 3) the flange's orientation there
    (contract A, B, C angles [deg] in {W}): with it, a controller's pose IK returns exactly the commands (a
    position alone leaves the arm's three redundant degrees of freedom open);
    residual_mm : shape=(M,) distance of the calibrated TCP at the commands from the target [mm] (the IK's own
    error); uncorrected_mm : shape=(M,) how far the calibrated robot's TCP lands from the target when the
    nominal model's IK solution is commanded [mm] (what the correction removes);
    ok : shape=(M,) both IK solutions converged within the joint limits;
    for pose targets (:func:`correct_poses`) also residual_rad : shape=(M,) the angle between the calibrated TCP
    frame at the commands and the target orientation [rad]; uncorrected_rad : shape=(M,) the same angle with the
    nominal model's IK solution commanded [rad] (both None for position targets)
    """

    q_rad: np.ndarray
    corrected_mm: np.ndarray
    corrected_abc_deg: np.ndarray
    residual_mm: np.ndarray
    uncorrected_mm: np.ndarray
    ok: np.ndarray
    residual_rad: np.ndarray | None = None
    uncorrected_rad: np.ndarray | None = None


#: a command this far from its seed on any joint [rad] has left the program's configuration (elbow, wrist flip)
CONFIGURATION_JUMP_RAD = np.pi / 2


def _warn_configuration(seeds: np.ndarray, q_rad: np.ndarray) -> None:
    """Log the targets whose commands leave the program's configuration (a wrist or elbow flip): a target in
    another frame than the calibration's, or an orientation the taught configuration cannot reach."""
    jump = np.abs(np.angle(np.exp(1j * (q_rad - seeds))))
    for i in np.nonzero(jump.max(axis=1) > CONFIGURATION_JUMP_RAD)[0]:
        j = int(np.argmax(jump[i]))
        log.warning("target %d: the commands leave the program's configuration (joint %d moves %.0f deg from its "
                    "seed); check that the target is in the calibration's frame", i + 1, j + 1,
                    np.degrees(jump[i, j]))


def _tcp(robot, params: ModelParams, q_rad) -> np.ndarray:
    return ball_positions(robot, params, q_rad)[0].pW


def correct_targets(robot, calibrated: ModelParams, nominal: ModelParams, targets_mm, q_seed_rad,
                    tol_mm: float = 1e-5) -> Correction:
    """The commands and corrected targets of ``targets_mm`` [mm], shape=(M, 3) in {W}, near the configurations
    ``q_seed_rad`` [rad], shape=(M, n) or (n,); ``calibrated`` and ``nominal`` share the base and the tool
    (see the module docstring); ``tol_mm``: the IK's position tolerance."""
    targets = np.atleast_2d(np.asarray(targets_mm, float))
    if targets.ndim != 2 or targets.shape[1] != 3 or not np.all(np.isfinite(targets)):
        raise CalibrationError(f"targets must be finite positions, shape (M, 3), got {targets.shape}", key="targets")
    seeds = np.broadcast_to(np.asarray(q_seed_rad, float), (len(targets), robot.n)).copy()
    nom = solve_ik_positions(robot, nominal, targets, seeds, pos_tol_mm=tol_mm)
    cal = solve_ik_positions(robot, calibrated, targets, nom.q_rad, pos_tol_mm=tol_mm)
    _warn_configuration(seeds, cal.q_rad)
    uncorrected = np.linalg.norm(_tcp(robot, calibrated, nom.q_rad) - targets, axis=1)
    corrected, abc = _nominal_pose(robot, nominal, cal.q_rad)
    return Correction(cal.q_rad, corrected, abc, cal.error_mm, uncorrected, nom.ok & cal.ok)


def _nominal_pose(robot, nominal: ModelParams, q_rad, R_tool=None) -> tuple[np.ndarray, np.ndarray]:
    """The nominal model's TCP position [mm] and frame orientation (contract A, B, C [deg]) at ``q_rad``."""
    p, R = tcp_poses(robot, nominal, q_rad, R_tool)
    T = np.broadcast_to(np.eye(4), (len(p), 4, 4)).copy()
    T[:, :3, :3] = R
    return p, np.array([matrix_to_pose(t)[3:] for t in T])


def correct_poses(robot, calibrated: ModelParams, nominal: ModelParams, targets_mm, abc_deg, q_seed_rad,
                  R_tool=None, tol_mm: float = 1e-5, tol_rad: float = 1e-8) -> Correction:
    """The commands and corrected targets of TCP poses: positions ``targets_mm`` [mm], shape=(M, 3), and
    orientations ``abc_deg`` (contract A, B, C [deg]), shape=(M, 3), of the tool frame in {W} (the flange frame
    rotated by ``R_tool``, identity by default), near ``q_seed_rad`` [rad]; 6-D IK (:mod:`calibrate.ik_pose`),
    first on the nominal model, then on the calibrated one from there. The corrected target is the nominal
    model's tool pose at the commands: a nominal controller's pose IK of it returns them."""
    targets = np.atleast_2d(np.asarray(targets_mm, float))
    abc = np.atleast_2d(np.asarray(abc_deg, float))
    if targets.shape != abc.shape or targets.shape[1:] != (3,) or not np.all(np.isfinite(np.c_[targets, abc])):
        raise CalibrationError(f"pose targets must be finite positions and A, B, C angles, shape (M, 3) each, got "
                               f"{targets.shape} and {abc.shape}", key="targets")
    R_t = np.array([pose_to_matrix(np.r_[0.0, 0.0, 0.0, a])[:3, :3] for a in abc])
    seeds = np.broadcast_to(np.asarray(q_seed_rad, float), (len(targets), robot.n)).copy()
    nom = solve_ik_poses(robot, nominal, targets, R_t, seeds, R_tool, tol_mm, tol_rad)
    cal = solve_ik_poses(robot, calibrated, targets, R_t, nom.q_rad, R_tool, tol_mm, tol_rad)
    _warn_configuration(seeds, cal.q_rad)
    p_u, R_u = tcp_poses(robot, calibrated, nom.q_rad, R_tool)
    corrected, corrected_abc = _nominal_pose(robot, nominal, cal.q_rad, R_tool)
    return Correction(cal.q_rad, corrected, corrected_abc, cal.error_mm, np.linalg.norm(p_u - targets, axis=1),
                      nom.ok & cal.ok, cal.error_rad, rotation_angle(R_u @ np.swapaxes(R_t, 1, 2)))


@dataclass(frozen=True)
class AxisDeviation:
    """An analytic-IK assumption of the nominal geometry and how far the calibrated geometry is from it.

    joints : the joints (1-based) concerned; assumption : ``parallel`` or ``intersecting``; angle_deg : angle
    between the calibrated axes (parallel) [deg]; distance_mm : common-normal distance of the calibrated axes
    (intersecting) [mm]; effect_mm : the TCP position change the deviation stands for at the zero configuration
    (the angle times the TCP's distance from the second axis, or the distance) [mm]
    """

    joints: tuple
    assumption: str
    angle_deg: float
    distance_mm: float
    effect_mm: float

    def describe(self) -> str:
        j = " and ".join(map(str, self.joints))
        if self.assumption == "parallel":
            return (f"joints {j} are parallel in the nominal model (analytic IK relies on it); calibrated they are "
                    f"{self.angle_deg:.4f} deg apart ({self.effect_mm:.3f} mm at the TCP of the zero configuration)")
        return (f"joint axes {j} intersect in the nominal model (analytic IK relies on it); calibrated they pass "
                f"{self.distance_mm:.4f} mm apart")


def _axes(robot, params: ModelParams) -> tuple[np.ndarray, np.ndarray]:
    """Joint axes (n, 3) and points on them (n, 3) in {0} at the zero configuration."""
    fr, _ = ball_positions(robot, params.with_(base=np.zeros(6)), np.zeros((1, robot.n)))
    return fr.z_prev[0], fr.o_prev[0]


def _line_distance(z1, o1, z2, o2) -> float:
    n = np.cross(z1, z2)
    if np.linalg.norm(n) < 1e-12:
        return float(np.linalg.norm(np.cross(o2 - o1, z1)))
    return float(abs((o2 - o1) @ n) / np.linalg.norm(n))


def ik_assumptions(robot, calibrated: ModelParams, nominal: ModelParams, angle_tol_deg: float = 1e-6,
                   distance_tol_mm: float = 1e-6) -> list[AxisDeviation]:
    """Every pair of consecutive joint axes that the nominal model has exactly parallel or exactly intersecting
    (what closed-form IK solvers of UR, ABB or FANUC arms assume), with the calibrated geometry's deviation;
    also the first and last axis of a nominal spherical wrist (intersecting in its centre at every configuration;
    the zero configuration is checked)."""
    zn, on = _axes(robot, nominal)
    zc, oc = _axes(robot, calibrated)
    tcp = ball_positions(robot, nominal.with_(base=np.zeros(6)), np.zeros((1, robot.n)))[0].p0[0]
    pairs = [(i, i + 1) for i in range(robot.n - 1)] + ([(robot.n - 3, robot.n - 1)] if robot.n >= 3 else [])
    out = []
    for i, j in pairs:
        nominal_angle = np.degrees(np.arccos(np.clip(abs(zn[i] @ zn[j]), -1.0, 1.0)))
        cal_angle = float(np.degrees(np.arccos(np.clip(abs(zc[i] @ zc[j]), -1.0, 1.0))))
        if nominal_angle < angle_tol_deg and j == i + 1:      # beyond neighbours parallelism depends on q
            out.append(AxisDeviation((i + 1, j + 1), "parallel", cal_angle, float("nan"),
                                     float(np.radians(cal_angle) * np.linalg.norm(tcp - on[j]))))
        elif nominal_angle >= angle_tol_deg and _line_distance(zn[i], on[i], zn[j], on[j]) < distance_tol_mm:
            d = _line_distance(zc[i], oc[i], zc[j], oc[j])
            out.append(AxisDeviation((i + 1, j + 1), "intersecting", float("nan"), d, d))
    return out
