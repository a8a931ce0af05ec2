"""Predicted calibration accuracy of a rod on a robot: Monte-Carlo over simulated MultiCal campaigns.

One *replicate* is one campaign as it happens in practice (paper Section 5.2), simulated in memory:

1. a true robot drawn from the priors (kinematic errors, joint compliances; :class:`Priors`) and a true rod
   that differs from the simulated compliance (the ``reference`` file, FEA) by a factor ``r_rod`` drawn from
   its prior (the paper measured 1.01-1.05 for steel rods, 1.23-2.30 for carbon);
2. the planned rod orientations at every clamping position (:func:`calibrate.plan.plan_poses`) reached by
   the true robot within the alignment tolerance; the device reads the deflected ball with its noise; the
   recorded fixture poses carry their uncertainty;
3. a validation set of random configurations measured by an external instrument (short rigid rod);
4. identification with compensation once per method, the methods being data (compliance files):
   ``none``; ``calc`` (closed form) and ``fea`` (the reference), both off by the true ``r_rod``; ``meas``, the
   rig's ``r_rod`` within its fit's uncertainty times the reference (paper Eq. 22); then validation.

With ``priors.rod_slip`` the true rod's deflection is off its elastic one at every point by a random
non-repeatable part (:mod:`calibrate.rod_slip`); no method compensates it: the budget gives it its own share.

The error budget of each method splits its mean-square validation error (:class:`AccuracySummary`):
``deflection`` — what the compensation leaves of the rod's deflection (this method minus calibrating with the
true rod's compliance); ``identification`` — the campaign's noise and fixture uncertainty propagated through
the identification, i.e. its observability, and the pull of the priors on weak parameters (calibrated with
the true rod minus the true robot itself); ``noise`` — what the true robot's own model shows on validation:
the instrument's noise; ``slip`` — the rod's non-repeatable deflection (calibrated with the true rod on the
campaign with the slip minus on the same campaign without it). :mod:`calibrate.budget` defines them.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import Method
from rodlab.core.frames import pose_to_matrix

from .campaign import Fixture
from .points_file import PointSet
from .compensations import RodDeflection, deflection_offsets
from .errors import CalibrationError
from .budget import AccuracySummary, BudgetShares, budget_shares
from .estimate import FitOptions
from .rod_slip import slip_directions, slip_offsets
from .identify import Observations, identify
from .ik import solve_ik_positions
from .kinematics import ModelParams, ball_positions
from .rod import Rod
from .robot_floor import robot_floor
from .simulate import random_truth
from .validate import ErrorStats, validate

__all__ = ["Priors", "SimulatedCampaign", "SimulatedReplicate", "simulate_replicate", "ReplicateOutcome",
           "AccuracySummary", "BudgetShares", "run_replicate", "summarise",
           "predict_accuracy", "VALIDATION_TOOL_MM"]

#: the validation rod (short, rigid) of the simulated instrument: tool [mm], mass [kg], COM in {T} [mm]
VALIDATION_TOOL_MM = (0.0, 0.0, 150.0)
VALIDATION_ROD = Rod.rigid(VALIDATION_TOOL_MM, 0.3, (0.0, 0.0, -60.0))


@dataclass(frozen=True)
class Priors:
    """What a replicate draws, with the paper's values as defaults.

    error_scale : scale of the kinematic errors (1 = ~0.5 mm / 0.05 deg per DH parameter) [-]
    joint_compliance : uniform range of joints 2..n compliance [rad/(N m)]
    device_noise_mm : MultiCal device noise per axis (1 sigma) [mm]
    instrument_noise_mm : validation instrument noise per axis (1 sigma) [mm]
    fixture_sigma : uncertainty of the recorded clamping poses (translation [mm], rotation [deg], 1 sigma)
    alignment_mm : how far from the datum point the robot stops (uniform +- per axis) [mm]
    r_rod : uniform range of the true / simulated compliance ratio of the rod [-] (Calc and FEA files are off
        by it; steel 1.01-1.05, carbon 1.23-2.30 in the paper)
    shape_sigma : how far the true compliance's shape departs from the simulated one (1 sigma of the entries
        of ``S - I`` in ``C_true = r S C_sim S^T``: joints, anisotropy, bonds the model does not see) [-]
    meas_sigma : relative uncertainty (1 sigma) of the rig's measurement (``C_F`` entries and r_rod) [-]
    validation_points : configurations of the validation set
    robot_floor_mm : the robot's own unmodelled error (:class:`~rodlab.calibrate.robot_floor.RobotFloor`: smooth
        joint-angle errors whose mean on rigid-tool validation is this) [mm]; 0 = none
    rod_slip : the rod's non-repeatable deflection (:mod:`~rodlab.calibrate.rod_slip`: slip and hysteresis in
        its joints), as the deflection under this many times its own weight in a random direction [-]; 0 = elastic
    """

    error_scale: float = 1.0
    joint_compliance: tuple = (3e-6, 6e-6)
    device_noise_mm: float = 0.003
    instrument_noise_mm: float = 0.02
    fixture_sigma: tuple = (0.01, 0.002)
    alignment_mm: float = 0.15
    r_rod: tuple = (1.01, 1.05)
    shape_sigma: float = 0.05
    meas_sigma: float = 0.01
    validation_points: int = 100
    robot_floor_mm: float = 0.0
    rod_slip: float = 0.0

    def __post_init__(self) -> None:
        for key in ("error_scale", "device_noise_mm", "instrument_noise_mm", "alignment_mm", "meas_sigma",
                    "shape_sigma", "robot_floor_mm", "rod_slip"):
            v = getattr(self, key)
            if not np.isfinite(v) or v < 0:
                raise CalibrationError(f"must be a finite number >= 0, got {v!r}", key=key)
        for key, (lo_ok, hi_ok) in (("joint_compliance", (0.0, 1e-4)), ("r_rod", (0.1, 10.0))):
            lo, hi = (float(x) for x in getattr(self, key))
            if not (lo_ok <= lo <= hi <= hi_ok):
                raise CalibrationError(f"expected a range LOW <= HIGH within [{lo_ok:g}, {hi_ok:g}], got "
                                       f"({lo:g}, {hi:g})", key=key)
        if len(self.fixture_sigma) != 2 or min(self.fixture_sigma) < 0:
            raise CalibrationError(f"expected (mm, deg) >= 0, got {self.fixture_sigma!r}", key="fixture_sigma")
        if int(self.validation_points) < 10:
            raise CalibrationError(f"at least 10 validation points, got {self.validation_points}",
                                   key="validation_points")


@dataclass(frozen=True)
class ReplicateOutcome:
    """One simulated campaign calibrated with every method.

    seed : the replicate's seed; r_true : the rod's true / reference compliance ratio [-]
    stats : {method: validation statistics after calibration}; ms_mm2 : {method: mean-square validation error
    [mm^2]}; ms_true_rod_mm2 : the same calibrated with the true rod [mm^2]; ms_clean_mm2 : of the true robot's
    own model [mm^2]; success : {method: identification converged}; before : validation of the nominal model;
    ms_true_no_slip_mm2 : calibrated with the true rod on the campaign without the rod's slip [mm^2] (NaN: the
    priors have no slip, or no budget was asked for)
    """

    seed: int
    r_true: float
    stats: dict
    ms_mm2: dict
    ms_true_rod_mm2: float
    ms_clean_mm2: float
    success: dict
    before: ErrorStats
    ms_true_no_slip_mm2: float = float("nan")


def _draw_truth(robot, tool_mm, base, priors: Priors, rng) -> ModelParams:
    truth = random_truth(robot, tool_mm, rng, priors.error_scale)
    lo, hi = priors.joint_compliance
    c = np.concatenate([[0.0], rng.uniform(lo, hi, robot.n - 1)])
    return truth.with_(c=c, base=np.asarray(base, float))


@dataclass(frozen=True)
class _Setup:
    """What every replicate of a prediction shares: the planned orientations {position: (k, n) [rad]}, the
    fixture, the rod's (FEA) compliance file the calibrator is given and the priors."""

    plan_q: dict
    fixture: Fixture
    reference: RodCompliance
    priors: Priors


def _reach(robot, truth, setup: _Setup, rng):
    """The true robot at every planned orientation, the ball within the alignment tolerance of the datum:
    (q [rad], group, datum-to-W transforms, forces in {W}) for the orientations it reached."""
    plan_q, fixture, reference, priors = setup.plan_q, setup.fixture, setup.reference, setup.priors
    keys = sorted(plan_q)
    Ts = {j: fixture.transform(j) for j in keys}
    seeds = np.concatenate([plan_q[j] for j in keys])
    group = np.concatenate([np.full(len(plan_q[j]), j) for j in keys])
    a = priors.alignment_mm
    targets = np.concatenate([Ts[j][:3, 3] + rng.uniform(-a, a, (len(plan_q[j]), 3)) @ Ts[j][:3, :3].T
                              for j in keys])
    forces = np.array([Ts[j][:3, :3] @ fixture.force_D_N for j in group])
    res = solve_ik_positions(robot, truth, targets, seeds, Rod.of(reference), forces, pull=False)
    return res.q_rad[res.ok], group[res.ok], Ts, forces[res.ok]


@dataclass(frozen=True)
class SimulatedCampaign:
    """One simulated campaign: q_rad (N, n) commanded angles; group (N,) clamping position; x_D_mm (N, 3) the
    device readings (with noise); force_W_N (N, 3); rod the rod the calibrator is given (:class:`~.rod.Rod`);
    recorded_poses {j: (6,)} the fixture poses as recorded (with their uncertainty); true_T {j: 4 x 4};
    slip_D_mm (N, 3) the rod's slip in the readings, in {D} [mm] (None: no slip), for :meth:`without_slip`."""

    q_rad: np.ndarray
    group: np.ndarray
    x_D_mm: np.ndarray
    force_W_N: np.ndarray
    recorded_poses: dict
    true_T: dict
    rod: Rod
    slip_D_mm: np.ndarray | None = None

    def without_slip(self) -> "SimulatedCampaign":
        """The same campaign (the same noise and fixture records) had the rod no slip."""
        if self.slip_D_mm is None:
            return self
        return replace(self, x_D_mm=self.x_D_mm - self.slip_D_mm, slip_D_mm=None)

    def observations(self) -> Observations:
        """What identification sees: the readings through the recorded poses (Eq. 2)."""
        x = np.empty_like(self.x_D_mm)
        for j in np.unique(self.group):
            m = self.group == j
            Tr = pose_to_matrix(self.recorded_poses[int(j)])
            x[m] = self.x_D_mm[m] @ Tr[:3, :3].T + Tr[:3, 3]
        return Observations(self.q_rad, x, self.force_W_N, self.rod, self.group.copy(), None, dict(self.true_T))


def _campaign(robot, truth, rod_true, floor, setup: _Setup, rng, slip_rng=None) -> SimulatedCampaign:
    """One campaign of the true robot ``truth`` (its unmodelled ``floor`` or None) with the true rod ``rod_true``:
    the planned orientations reached, the device's readings and the fixture poses as recorded; the rod's slip
    from ``slip_rng`` (default ``rng``)."""
    fixture, reference, priors = setup.fixture, setup.reference, setup.priors
    q, group, Ts, F = _reach(robot, truth, setup, rng)
    if q.shape[0] < 6:
        raise CalibrationError(f"the true robot reached only {q.shape[0]} planned orientations", key="plan")
    qt = q if floor is None else floor.angles(q)                      # the angles the joints really take
    fr, _ = ball_positions(robot, truth, qt, Rod.of(reference), force_W_N=F)
    pW = fr.pW + deflection_offsets(robot, truth, qt, F, rod_true)
    slip_W = None
    if priors.rod_slip:                                              # the rod's non-repeatable part
        u = slip_directions(rng if slip_rng is None else slip_rng, len(q))
        slip_W = slip_offsets(robot, truth, qt, F, rod_true, priors.rod_slip, u)
        pW = pW + slip_W
    st, sr = priors.fixture_sigma
    xD = np.empty_like(pW)
    slip_D = None if slip_W is None else np.empty_like(pW)
    recorded = {}
    for j in np.unique(group):
        m = group == j
        T = Ts[int(j)]
        xD[m] = (pW[m] - T[:3, 3]) @ T[:3, :3] + rng.normal(0, priors.device_noise_mm, (int(m.sum()), 3))
        if slip_D is not None:
            slip_D[m] = slip_W[m] @ T[:3, :3]
        pose = np.asarray(fixture.poses[int(j)], float)
        if int(j) != fixture.world_position:
            pose = pose + np.concatenate([rng.normal(0, st, 3), rng.normal(0, sr, 3)])
        recorded[int(j)] = pose
    return SimulatedCampaign(q, group, xD, F, recorded, {int(j): Ts[int(j)] for j in np.unique(group)},
                             Rod.of(reference), slip_D)


def _validation(robot, truth, priors: Priors, rng, floor=None) -> tuple[PointSet, PointSet]:
    """(measured, exact) validation points: random configurations within 60 % of the limits, short rigid rod."""
    tool = np.asarray(VALIDATION_TOOL_MM, float)
    vtrue = truth.with_(tool=tool + rng.normal(0, 0.05, 3))
    lo, hi = np.deg2rad(robot.limits_deg[:, 0]), np.deg2rad(robot.limits_deg[:, 1])
    vq = rng.uniform(lo * 0.6, hi * 0.6, (int(priors.validation_points), robot.n))
    fr, _ = ball_positions(robot, vtrue, vq if floor is None else floor.angles(vq), VALIDATION_ROD)
    noisy = fr.pW + rng.normal(0, priors.instrument_noise_mm, fr.pW.shape)

    def pts(x):
        return PointSet(np.rad2deg(vq), x, tool, VALIDATION_ROD.mass_kg, VALIDATION_ROD.com_T_mm.copy())
    return pts(noisy), pts(fr.pW)


def _congruent(rod: RodCompliance, r: float, sigma: float, method: Method, rng, C_g=None) -> RodCompliance:
    """``r S C S^T`` for C_F and C_g (or the given ``C_g``), ``S = I + sigma N(0, 1)``: symmetric and positive
    semi-definite like the original, its shape perturbed."""
    S = np.eye(3) + sigma * rng.standard_normal((3, 3))
    Cg = r * S @ rod.C_g @ S.T if C_g is None else C_g
    return RodCompliance(rod.rod, method, r * S @ rod.C_F @ S.T, Cg, rod.mass_kg, rod.com_T_mm, rod.tool_mm,
                         float(r), dict(rod.provenance, simulated_from=str(rod.method)))


def _true_rod(reference: RodCompliance, priors: Priors, rng) -> tuple[float, RodCompliance]:
    """(r_rod, the rod as it is): ``r`` from its prior, the shape within ``shape_sigma`` of the reference."""
    r = float(rng.uniform(*priors.r_rod))
    return r, _congruent(reference, r, priors.shape_sigma, Method.MEAS, rng)


def _method_files(methods, reference: RodCompliance, calc: RodCompliance | None, true: RodCompliance,
                  r_true: float, priors, rng):
    """{method: compliance file, None for method none} as the files stand to the true rod: calc and fea as
    computed; meas the rig's ``C_F`` (the true one within ``meas_sigma``) and ``C_g = r_meas C_g,sim`` (paper
    Eq. 22)."""
    r_meas = r_true * (1.0 + priors.meas_sigma * rng.standard_normal())
    meas = _congruent(true, 1.0, priors.meas_sigma, Method.MEAS, rng, C_g=r_meas * reference.C_g)
    out = {}
    for m in methods:
        if m is Method.NONE:
            out[m] = None
        elif m is Method.CALC:
            if calc is None:
                raise CalibrationError("method calc needs the closed-form compliance file", key="methods")
            out[m] = calc
        elif m is Method.FEA:
            out[m] = reference
        else:
            out[m] = meas
    return out


def _calibrated_ms(robot, obs, rod: Rod, comp: RodDeflection, pts: PointSet):
    res = identify(robot, obs, rod, [comp], FitOptions(expected_noise_mm=None))
    stats, err, _ = validate(robot, res.params, pts)
    return stats, float(np.mean(err ** 2)), bool(res.success)


@dataclass(frozen=True)
class SimulatedReplicate:
    """The draws of one replicate: truth, the true rod, the campaign, the validation points (measured and
    exact) and the compensation of every method."""

    truth: ModelParams
    r_true: float
    rod_true: RodCompliance
    campaign: SimulatedCampaign
    points: PointSet
    points_exact: PointSet
    files: dict


def simulate_replicate(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                       calc: RodCompliance | None, methods, priors: Priors = Priors(), seed: int = 0
                       ) -> SimulatedReplicate:
    """The draws of replicate ``seed`` (see the module docstring); :func:`run_replicate` calibrates them."""
    rng = np.random.default_rng(seed)
    methods = [Method.parse(m, "method") for m in methods]
    truth = _draw_truth(robot, reference.tool_mm, base, priors, rng)
    r_true, rod_true = _true_rod(reference, priors, rng)
    floor = robot_floor(robot, priors.robot_floor_mm, seed)           # None at 0: the same draws as without
    camp = _campaign(robot, truth, rod_true, floor, _Setup(plan_q, fixture, reference, priors), rng,
                     np.random.default_rng([seed, 46]))
    pts, pts_exact = _validation(robot, truth, priors, rng, floor)
    files = _method_files(methods, reference, calc, rod_true, r_true, priors, rng)
    return SimulatedReplicate(truth, r_true, rod_true, camp, pts, pts_exact, files)


def run_replicate(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                  calc: RodCompliance | None, methods, priors: Priors = Priors(), seed: int = 0,
                  budget: bool = True) -> ReplicateOutcome:
    """One replicate (see the module docstring). ``plan_q``: {position: (k, n) planned joint angles [rad]};
    ``base``: nominal pose of {0} in {W} [mm, deg]; ``reference``: the rod's simulated (FEA) compliance file;
    ``calc``: its closed-form file (for method calc); ``budget``: also calibrate with the true rod (one more
    identification) and validate the true robot, for the error budget."""
    sim = simulate_replicate(robot, plan_q, fixture, base, reference, calc, methods, priors, seed)
    obs, pts = sim.campaign.observations(), sim.points
    stats, ms, ok = {}, {}, {}
    rod = Rod.of(reference)
    for m, file in sim.files.items():
        stats[m], ms[m], ok[m] = _calibrated_ms(robot, obs, rod, RodDeflection.of(file), pts)
    ms_true = ms_clean = ms_no_slip = float("nan")
    if budget:
        exact = RodDeflection.of(sim.rod_true, "true rod")
        ms_true = _calibrated_ms(robot, obs, rod, exact, pts)[1]
        if sim.campaign.slip_D_mm is not None:                        # the slip's own share: one more fit
            ms_no_slip = _calibrated_ms(robot, sim.campaign.without_slip().observations(), rod, exact, pts)[1]
        _, err, _ = validate(robot, sim.truth, pts)                  # the true robot itself, base / tool refitted
        ms_clean = float(np.mean(err ** 2))
    before = validate(robot, ModelParams.nominal(robot, pts.tool_mm), pts)[0]
    return ReplicateOutcome(int(seed), sim.r_true, stats, ms, ms_true, ms_clean, ok, before, ms_no_slip)


def _finite_mean(values) -> float:
    v = np.asarray(values, float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else float("nan")


def summarise(outcomes: list[ReplicateOutcome], methods) -> list[AccuracySummary]:
    """One :class:`AccuracySummary` per method over the replicates."""
    out = []
    ms_true, ms_clean, ms_no_slip = (_finite_mean([getattr(o, k) for o in outcomes])
                                     for k in ("ms_true_rod_mm2", "ms_clean_mm2", "ms_true_no_slip_mm2"))
    for m in (Method.parse(x, "method") for x in methods):
        got = [o for o in outcomes if m in o.stats]
        means = np.array([o.stats[m].mean_mm for o in got])
        if not got:
            raise CalibrationError(f"no replicate has method {m}", key="methods")
        ms = float(np.mean([o.ms_mm2[m] for o in got]))
        out.append(AccuracySummary(
            m, float(means.mean()), float(np.mean([o.stats[m].max_mm for o in got])),
            float(np.mean([o.stats[m].median_mm for o in got])), float(np.percentile(means, 5)),
            float(np.percentile(means, 95)), float(np.sqrt(ms)), budget_shares(ms, ms_true, ms_clean, ms_no_slip),
            len(got),
            sum(not o.success[m] for o in got), tuple(float(v) for v in means)))
    return out


def predict_accuracy(robot, plan_q: dict, fixture: Fixture, base, reference: RodCompliance,
                     calc: RodCompliance | None = None, methods=(Method.NONE, Method.FEA, Method.MEAS),
                     priors: Priors = Priors(), replicates: int = 20, seed: int = 0,
                     budget: bool = True) -> list[AccuracySummary]:
    """Serial Monte-Carlo (``replicates`` campaigns, seeds ``seed .. seed + replicates - 1``); the study runs
    :func:`run_replicate` as Dask tasks and :func:`summarise` on the results instead."""
    outcomes = [run_replicate(robot, plan_q, fixture, base, reference, calc, methods, priors, seed + i, budget)
                for i in range(int(replicates))]
    return summarise(outcomes, methods)

