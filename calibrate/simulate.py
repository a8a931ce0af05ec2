"""Synthetic MultiCal campaigns (contract files) from a known truth: the project's own test data.

A truth robot (random kinematic errors of a given scale, joint compliances), a fixture with clamping
positions in front of the robot (device frames tilted so their axes are 54.7 deg from the plumb line), a
rod (its true compliance and tool), device and instrument noise. For each clamping position the true
robot aligns the (deflected) ball with the datum point in ``k`` rod orientations (numeric IK) up to an
alignment tolerance; the device reads the remaining offset in {D_j}. A validation set of random
configurations is measured by an external instrument with a short rigid rod.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from rodlab.core.compliance import RodCompliance, write_compliance
from rodlab.core.errors import expect_type
from rodlab.core.fileio import atomic_write_json, atomic_write_text
from rodlab.core.frames import matrix_to_pose

from .errors import CalibrationError
from .compensations import COMPENSATIONS, Compensation, Poses, RodDeflection, deflection_offsets
from .effects import CAMPAIGN_EFFECTS, complete_campaign_effects
from .ik import random_configurations, solve_ik_groups, solve_ik_positions
from .kinematics import ModelParams, ball_positions
from .robot import Robot
from .rod import Rod
from .robot_floor import RobotFloor, robot_floor
from .setup_layout import CONTACT_FORCE_D_N, fixture_layout, standard_base, standard_fixture
from .probe import simulated_probe_text
from .device import write_device

__all__ = ["CampaignSpec", "simulate_campaign", "random_truth", "standard_base", "fixture_layout", "standard_fixture",
           "RobotFloor", "robot_floor"]


#: the largest device noise a simulated campaign takes [mm] (a dial gauge's is 0.001-0.01 mm)
MAX_DEVICE_NOISE_MM = 0.5


@dataclass
class CampaignSpec:
    """positions, orientations per position, noise [mm], joint resolution [deg], alignment [mm], error scale;
    checked on construction (whole numbers >= 1, finite numbers >= 0, a device noise of at most
    :data:`MAX_DEVICE_NOISE_MM`: the library's noise is in mm where the CLI's flag is in um)."""

    positions: int = 5
    orientations: int = 6
    device_noise_mm: float = 0.003
    instrument_noise_mm: float = 0.02
    q_resolution_deg: float = 1e-4
    alignment_mm: float = 0.15
    fixture_noise_mm_deg: tuple = (0.01, 0.002)
    probe_accuracy_mm: float = 0.005
    error_scale: float = 1.0
    validation_points: int = 100
    seed: int = 0

    def __post_init__(self) -> None:
        for key in ("positions", "orientations", "validation_points"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
                raise CalibrationError(f"CampaignSpec.{key}: expected a whole number >= 1, got {v!r}", key=key)
        for key in ("device_noise_mm", "instrument_noise_mm", "q_resolution_deg", "alignment_mm", "probe_accuracy_mm",
                    "error_scale"):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.floating)) or not np.isfinite(v) or v < 0:
                raise CalibrationError(f"CampaignSpec.{key}: expected a finite number >= 0, got {v!r}", key=key)
        if self.device_noise_mm > MAX_DEVICE_NOISE_MM:
            raise CalibrationError(f"CampaignSpec.device_noise_mm = {self.device_noise_mm:g} mm: the noise is in mm (the "
                                   f"CLI's --noise-um {self.device_noise_mm:g} is {self.device_noise_mm / 1000:g} mm); "
                                   f"a MultiCal device's is 0.003 mm, at most {MAX_DEVICE_NOISE_MM:g} mm is taken",
                                   key="device_noise_mm")


def random_truth(robot, tool_mm, rng, scale=1.0) -> ModelParams:
    """A plausible real robot: DH errors ~0.5 mm / 0.05 deg, joint compliances 3-6 urad/(N m)."""
    n = robot.n
    p = ModelParams.nominal(robot, tool_mm)
    par = set(robot.parallel_rows())
    d = p.d + scale * rng.normal(0, 0.5, n) * np.array([0 if i in par else 1 for i in range(n)])
    a = p.a + scale * rng.normal(0, 0.5, n)
    al = p.alpha + scale * np.deg2rad(rng.normal(0, 0.05, n))
    be = p.beta + scale * np.deg2rad(rng.normal(0, 0.05, n)) * np.array([1 if i in par else 0 for i in range(n)])
    th = p.theta_offset + scale * np.deg2rad(rng.normal(0, 0.06, n))
    c = np.concatenate([[0.0], rng.uniform(3e-6, 6e-6, n - 1)])
    return p.with_(d=d, a=a, alpha=al, beta=be, theta_offset=th, c=c)


def _reach_positions(robot, truth, rod, Ts: dict, forces: dict, spec, rng) -> dict:
    """``spec.orientations`` configurations [rad] per clamping position (dict j -> (k, n) array) with which the
    true robot brings the ball within the alignment tolerance of the datum point, each from a random seed (a
    different rod orientation each time): position IK for every position in one batch of ``3 k`` seeds each,
    repeated for the positions still short, at most ``60 k`` tries per position."""
    k = spec.orientations
    m = 3 * k
    got = {j: [] for j in Ts}
    for _ in range(20):
        short = [j for j in Ts if len(got[j]) < k]
        if not short:
            break
        seeds = random_configurations(robot, rng, len(short) * m)
        targets = {j: Ts[j][:3, 3] + rng.uniform(-spec.alignment_mm, spec.alignment_mm, (m, 3)) @ Ts[j][:3, :3].T
                   for j in short}
        for j, q in solve_ik_groups(robot, truth, targets, seeds, rod, forces).items():
            got[j] += list(q)
    for j in Ts:
        if len(got[j]) < k:
            raise CalibrationError(f"clamping position {j}: only {len(got[j])} of {k} rod orientations are "
                                   f"reachable", key="positions")
    return {j: np.array(got[j][:k]) for j in Ts}


def simulate_campaign(robot, rod: RodCompliance, out_dir, spec: CampaignSpec = CampaignSpec(), *,
                      rod_true: RodCompliance | None = None, effects=None, compensations: Sequence[Compensation] = (),
                      temp_K_per_s: float = 0.0, device=None) -> dict:
    """Write ``multical.campaign.csv``, ``multical.fixture.json``, ``multical.validation.csv``, ``truth.json``
    and the rod file into ``out_dir`` (with a device also ``multical.device.json`` and ``multical.probe.csv``,
    its features probed at the true clamping poses to ``spec.probe_accuracy_mm``); return the truth.

    rod_true : the rod as it really is (default: ``rod``, the file the calibrator is given; a ``rod_deflection``
        effect scales it further);
    effects : physics the calibrator's model leaves out, ``{name: parameters}`` or ``[(name, parameters), ...]``
        (an effect may repeat in the list form) with the names and parameters of
        :data:`rodlab.calibrate.effects.CAMPAIGN_EFFECTS` (e.g. ``{"fixture_pose": {"position": 2,
        "offset_mm": [0.1, 0, 0]}}``; missing magnitudes take the effect's example);
    compensations : what the true rod does beyond its deflection (which ``rod_true`` gives), as the entries of
        :data:`~rodlab.calibrate.compensations.COMPENSATIONS` a calibration would remove it with: each one's
        offsets (true robot, true angles, contact forces, the recorded temperatures) move the readings, e.g.
        :class:`~rodlab.calibrate.compensations.ThermalGrowth`;
    temp_K_per_s : the room warms from 22 degC at that rate during the campaign (the ``temp_C`` column records
        it);
    device : a :class:`~calibrate.device.Device` as built: the campaign then holds its sensors' raw readings
        (``s1_mm, s2_mm, s3_mm``, each with the device noise), the springs push the ball with the force at each
        reading, and ``multical.device.json`` is written (the caller may write another, e.g. a nominal one)."""
    expect_type(robot, Robot, "robot", "load one with rodlab.calibrate.resolve_robot('tx90' or a robot file)")
    expect_type(rod, RodCompliance, "rod", "a compliance file: rodlab.calc_rod_compliance(design) or "
                "rodlab.read_compliance(FILE)")
    active = complete_campaign_effects(effects)
    _check_compensations(compensations)
    for m, p in active:
        m.check_layout(spec.positions, spec.positions * spec.orientations, robot.n, p)
    rng = np.random.default_rng(spec.seed)
    out = Path(out_dir)
    rod_true = rod_true or rod
    for m, p in active:
        rod_true = m.true_rod(rod_true, p)
    truth = random_truth(robot, rod.tool_mm, rng, spec.error_scale).with_(base=standard_base())
    wp, Ts = fixture_layout(spec.positions, rng)
    world = _World(truth, Rod.of(rod), rod_true, Ts, active, tuple(compensations), temp_K_per_s, device)
    readings = _readings(robot, world, spec, rng)
    xD, corrupted = _corrupt(readings, spec, active)
    readings = replace(readings, xD=xD)
    out.mkdir(parents=True, exist_ok=True)             # after every check and the reachability of the poses
    _write_campaign(out / "multical.campaign.csv", robot, readings, device)
    recorded = _recorded_fixture(Ts, wp, spec, rng, active)
    atomic_write_json(out / "multical.fixture.json", {"format": "rodlab.fixture/1", "world_position": wp,
                                                      "positions": recorded,
                                                      "contact_force_N": _force_at_datum(device).tolist()})
    if device is not None:
        write_device(device, out / "multical.device.json")
        atomic_write_text(out / "multical.probe.csv", simulated_probe_text(Ts, device, spec.probe_accuracy_mm,
                                                                           np.random.default_rng([spec.seed, 3])))
    _write_validation(out / "multical.validation.csv", robot, truth, spec, rng, active)
    write_compliance(rod, out / "rod.compliance.json")
    t = _truth_record(robot, world, spec, corrupted)
    atomic_write_json(out / "truth.json", t)
    return t


@dataclass(frozen=True)
class _World:
    """What the simulated campaign really is (the calibrator sees it only through the readings): the true robot
    model, the rod the calibrator is given (its tool, weight and compliance), the rod as it really is (its
    compliance deflects the ball), the true clamping poses {j: 4 x 4 in {W}}, the active effects [(effect,
    parameters)], the compensations' true effects, the room's warming rate [K/s] and the device as built (None:
    the paper's, constant contact force)."""

    truth: ModelParams
    rod: Rod
    rod_true: RodCompliance
    Ts: dict
    active: list
    compensations: tuple = ()
    temp_K_per_s: float = 0.0
    device: object = None


@dataclass
class _Readings:
    """The campaign as recorded: position, point index within it, joint angles as read [deg], device readings
    in {D} [mm], time [s], temperature [degC], one row per point."""

    position: np.ndarray
    point: np.ndarray
    q_deg: np.ndarray
    xD: np.ndarray
    time_s: np.ndarray
    temp_C: np.ndarray

    def labels(self) -> list:
        return [f"{j}.{i}" for j, i in zip(self.position, self.point)]     # as Campaign.labels


def _true_angles(q: np.ndarray, active) -> np.ndarray:
    for m, p in active:
        q = m.joint_angles(q, p)
    return q


def _force_at_datum(device) -> np.ndarray:
    """The contact force in {D} [N] with the ball at the datum point: the device's springs', else the paper's."""
    if device is None or not device.has_springs:
        return CONTACT_FORCE_D_N.copy()
    return device.force_D(device.zero_mm[None, :])[0]


def _device_noise(rng, sigma_mm: float, m: int, device) -> np.ndarray:
    """Device noise of m points in {D} [mm]: per coordinate, or each sensor's reading through the axes."""
    n = rng.normal(0, sigma_mm, (m, 3))
    return n if device is None else device.positions(device.zero_mm + n)


def _spring_loaded(robot, world: _World, qt, T, Fm):
    """Ball centres in {W} (true robot, true rod deflected) at the true angles ``qt`` of a clamping position of
    pose ``T`` under the contact forces ``Fm`` in {W}; with a device's springs the force is the one at each point's
    readings (one update: a spring rate changes it by ~1 %)."""
    truth, rod, rod_true, device = world.truth, world.rod, world.rod_true, world.device

    def centres(F):
        fr, tau = ball_positions(robot, truth, qt, rod, force_W_N=F)
        q_loaded = qt
        for m, p in world.active:
            q_loaded = m.torque_angles(q_loaded, tau, p)
        if q_loaded is not qt:                      # a joint's spring beyond linear: at the torques just found
            fr, _ = ball_positions(robot, truth, q_loaded, rod, force_W_N=F)
        return fr, fr.pW + deflection_offsets(robot, truth, q_loaded, F, rod_true)
    fr, pW = centres(Fm)
    if device is not None and device.has_springs:
        Tinv = np.linalg.inv(T)
        Fm = device.force_D(device.readings(pW @ Tinv[:3, :3].T + Tinv[:3, 3])) @ T[:3, :3].T
        fr, pW = centres(Fm)
    return fr, pW


def _reaim(robot, truth, rod, forces: dict, reached: dict) -> dict:
    """The operator aligns the ball on the device's readings, so the rod's deflection under its weight and the
    contact force is taken out of the alignment: each configuration moved (IK from itself) until the deflected
    ball is where the undeflected one was; one that IK cannot move keeps its place."""
    keys = list(reached)
    q = np.concatenate([reached[j] for j in keys])
    F = np.concatenate([np.broadcast_to(forces[j], (len(reached[j]), 3)) for j in keys])
    fr, _ = ball_positions(robot, truth, q, rod, force_W_N=F)
    res = solve_ik_positions(robot, truth, fr.pW - deflection_offsets(robot, truth, q, F, rod), q, rod, F)
    q = np.where(res.ok[:, None], res.q_rad, q)
    edges = np.cumsum([0] + [len(reached[j]) for j in keys])
    return {j: q[a:b] for j, a, b in zip(keys, edges[:-1], edges[1:])}


def _readings(robot, world: _World, spec, rng) -> _Readings:
    """What the device reads at every clamping position: the true robot with the true rod deflected by its
    weight and the contact force, the effects' offsets, device noise, quantised joint angles."""
    truth, rod, Ts, active, device = world.truth, world.rod, world.Ts, world.active, world.device
    forces = {j: Ts[j][:3, :3] @ _force_at_datum(device) for j in Ts}
    reached = _reach_positions(robot, truth, rod, Ts, forces, spec, rng)
    if device is not None:
        reached = _reaim(robot, truth, rod, forces, reached)
    cols: dict = {"position": [], "point": [], "q_deg": [], "xD": [], "time_s": [], "temp_C": []}
    t = 0.0
    for j in range(1, spec.positions + 1):
        q = reached[j]
        qt = _true_angles(q, active)                                   # the angles the joints really take
        for eff, p in active:
            qt = eff.position_angles(qt, j, p)
        m = len(q)
        Fm = np.broadcast_to(forces[j], (m, 3))
        fr, pW = _spring_loaded(robot, world, qt, Ts[j], Fm)
        Tinv = np.linalg.inv(Ts[j])
        xD = pW @ Tinv[:3, :3].T + Tinv[:3, 3] + _device_noise(rng, spec.device_noise_mm, m, device)
        times = t + np.cumsum(rng.uniform(40, 120, m))
        t = float(times[-1])
        temps = np.round(22.0 + world.temp_K_per_s * np.round(times), 2)
        for c in world.compensations:
            grow_W = c.offsets(robot, truth, Poses(qt, Fm, temps, rod))
            xD = xD + grow_W @ Tinv[:3, :3].T
        for eff, p in active:
            grow = eff.reading_offset_W(fr, times, p)
            if grow is not None:
                xD = xD + grow @ Ts[j][:3, :3]
        cols["position"].append(np.full(m, j))
        cols["point"].append(np.arange(1, m + 1))
        cols["q_deg"].append(np.round(np.rad2deg(q) / spec.q_resolution_deg) * spec.q_resolution_deg)
        cols["xD"].append(xD)
        cols["time_s"].append(times)
        cols["temp_C"].append(temps)
    return _Readings(**{k: np.concatenate(v) for k, v in cols.items()})


def _corrupt(readings: _Readings, spec, active) -> tuple[np.ndarray, dict]:
    """Gross errors of single readings (outliers), from a generator of their own: the other draws of the
    campaign stay those of the same seed without them."""
    xD, done = readings.xD, {}
    rng = np.random.default_rng([spec.seed, 1])
    for m, p in active:
        xD, info = m.corrupt(xD, readings.labels(), rng, p)
        done.update(info)
    return xD, done


def _write_campaign(path: Path, robot, r: _Readings, device=None) -> None:
    """The campaign file: x, y, z in {D}, or with a device its sensors' readings (as they read them)."""
    cells = r.xD if device is None else device.readings(r.xD)
    cols = "x_mm,y_mm,z_mm" if device is None else "s1_mm,s2_mm,s3_mm"
    rows = [f"{j},{i}," + ",".join(f"{v:.4f}" for v in q) + "," + ",".join(f"{v:.4f}" for v in x)
            + f",{ts:.0f},{tc:.2f}" for j, i, q, x, ts, tc in zip(r.position, r.point, r.q_deg, cells, r.time_s, r.temp_C)]
    atomic_write_text(path, "position,point," + ",".join(f"q{i + 1}" for i in range(robot.n))
                      + f",{cols},time_s,temp_C\n" + "\n".join(rows) + "\n")


def _recorded_fixture(Ts: dict, wp: int, spec, rng, active) -> dict:
    """The clamping poses as the fixture file records them: measured to the fixture noise (the world position
    exactly), and as the effects misrecord them."""
    rec = {}
    st, sr = spec.fixture_noise_mm_deg
    for j, T in Ts.items():
        pr = np.array(matrix_to_pose(T), float)
        if j != wp:
            pr = pr + np.concatenate([rng.normal(0, st, 3), rng.normal(0, sr, 3)])
        for m, p in active:
            pr = m.recorded_fixture(j, pr, p)
        rec[str(j)] = [round(float(v), 6) for v in pr]
    return rec


def _write_validation(path: Path, robot, truth, spec, rng, active) -> None:
    """Validation: random reachable configurations measured by an external instrument with a short rigid rod."""
    vt = np.array([0.0, 0.0, 150.0])
    vtrue = truth.with_(tool=vt + rng.normal(0, 0.05, 3))
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    vq = rng.uniform(lo * 0.6, hi * 0.6, (spec.validation_points, robot.n))
    vrod, qt = Rod.rigid(vt, 0.3, [0, 0, -60]), _true_angles(vq, active)
    fr, tau = ball_positions(robot, vtrue, qt, vrod)
    q_loaded = qt
    for m, p in active:                         # a joint's spring beyond linear, under the validation rod
        q_loaded = m.torque_angles(q_loaded, tau, p)
    if q_loaded is not qt:
        fr, _ = ball_positions(robot, vtrue, q_loaded, vrod)
    vx = fr.pW + rng.normal(0, spec.instrument_noise_mm, fr.pW.shape)
    lines = ["# tool_mm: 0, 0, 150", "# rod_mass_kg: 0.3", "# rod_com_T_mm: 0, 0, -60", "# temp_C: 22.0",
             ",".join(f"q{i + 1}" for i in range(robot.n)) + ",x_mm,y_mm,z_mm"]
    lines += [",".join(f"{v:.4f}" for v in np.rad2deg(q)) + "," + ",".join(f"{v:.3f}" for v in x)
              for q, x in zip(vq, vx)]
    atomic_write_text(path, "\n".join(lines) + "\n")


def _check_compensations(compensations) -> None:
    """The simulator's compensations: registry entries beside the rod's deflection (``rod_true`` is that)."""
    for c in compensations:
        if not isinstance(c, Compensation):
            raise CalibrationError(f"compensations: {c!r} is not a compensation (one of {', '.join(COMPENSATIONS)})",
                                   key="compensations")
        if isinstance(c, RodDeflection):
            raise CalibrationError("compensations: the simulated rod deflects by its compliance already; give the "
                                   "true rod as rod_true instead of a rod_deflection entry", key="compensations")


def _truth_record(robot, world: _World, spec, corrupted: dict) -> dict:
    """``truth.json``: the true model, fixture poses and every simulated effect with its parameters."""
    truth, rod, rod_true, Ts, active = world.truth, world.rod, world.rod_true, world.Ts, world.active
    t = {"format": "rodlab.truth.campaign/1", "seed": spec.seed, "spec": spec.__dict__,
         "true_base_pose_W": truth.base.tolist(), "true_tool_mm": truth.tool.tolist(),
         "dtheta_deg": np.rad2deg(truth.theta_offset - np.deg2rad(robot.theta_offset_deg)).tolist(),
         "d_mm": truth.d.tolist(), "a_mm": truth.a.tolist(), "alpha_deg": np.rad2deg(truth.alpha).tolist(),
         "beta_deg": np.rad2deg(truth.beta).tolist(), "c_rad_per_Nm": truth.c.tolist(),
         "true_fixture_poses_W": {str(j): matrix_to_pose(T).tolist() for j, T in Ts.items()}}
    for m in CAMPAIGN_EFFECTS.values():                 # every effect's truth keys, empty when not simulated
        t.update(m.truth(None))
    for m, p in active:
        for k, v in m.truth(p).items():
            t[k] = {**t[k], **v} if isinstance(v, dict) and isinstance(t.get(k), dict) else v
    simulated = {k: v for c in COMPENSATIONS.values() for k, v in c.truth_of(None).items()}
    simulated.update({k: v for c in world.compensations for k, v in type(c).truth_of(c).items()})
    t.update({**simulated, "temp_K_per_s": float(world.temp_K_per_s),
              "r_true": float(rod_true.C_F[1, 1] / rod.C_F[1, 1]) if rod.C_F[1, 1] else 1.0,
              "effects": [{"effect": str(m.effect), **p} for m, p in active], **corrupted})
    return t
