"""Whether a refused campaign's files are mixed up: one joint's readings reversed, two clamping positions swapped.

A controller's export or a robot file whose joint K turns the other way (a URDF axis ``0 0 -1``, a DH row written
for the opposite convention, a column negated by a script), or a campaign whose position labels of two clampings
are swapped against the fixture file, gives a campaign the identification cannot fit with plausible parameters:
it diverges or finds a mirrored chain. An IRB 4600 trial: joint 2 reversed gave ``dtheta_2`` and ``alpha_2``
+180 deg, ``a_1`` and ``a_2`` with their signs flipped, 13 um rms and a held-out error of 1435 mm (the diagnosis's
suspect: a periodic error of joint 2); joint 3 reversed or positions 4 and 5 swapped, residuals of 345-744 mm rms.

Where a calibration is refused for parameters beyond their bounds or residuals the noise model does not explain
by a material margin, each joint's readings are negated in turn, each pair of q columns exchanged and each pair of
positions swapped, and the campaign identified again. A mix-up whose undoing gives plausible parameters and fits at least as well
(where the given fit's parameters were beyond their bounds: the mirrored chain fits, 13 um against 7 um for the
trial's joint 2; :data:`TIE_GAIN`) or to at most :data:`MIXUP_GAIN` of the rms (gross residuals, plausible
parameters) is named.

Instrument points are screened before they are identified (:func:`points_mixup`): their identification of a
reversed joint is the slow kind (1-2.5 min on the UR5 tracker data with joint 2 or 3 negated, for a mirrored
chain or parameters far beyond their bounds), while the nominal model with base and tool registered from scratch
(:func:`~calibrate.observations.register_base_and_tool`, ~0.1 s) tells a robot a few mm off its nominal model
from one whose joint turns the other way (hundreds of mm).
"""
from __future__ import annotations

import itertools
import logging
from dataclasses import replace
from typing import Callable

import numpy as np

from .errors import CalibrationError
from .identify import campaign_observations, identify
from .kinematics import ModelParams
from .mixup import Mixup
from .observations import register_base_and_tool
from .points import identify_points, points_observations
from .socket_check import check_sockets
from .socket_fit import identify_sockets, socket_start
from .sockets import SocketReadings
from .target_change import target_change
from .trust import bound_warnings, gross

__all__ = ["Mixup", "find_mixup", "campaign_mixup", "points_mixup", "sockets_mixup", "refuse_mixed_up_joints",
           "MIXUP_GAIN", "QUICK_NFEV", "NOMINAL_GROSS_MM"]

log = logging.getLogger(__name__)

#: where the given fit is gross but plausible, undoing the mix-up must bring the rms to at most this share of it:
#: take at least half its sum of squares away (a real robot's own errors set a floor the undoing cannot go below:
#: an independent trial's y and z columns exchanged fitted 32.7 um against 61.2 um as given, its floor 33 um;
#: a share of 0.5 of the rms had left both it and a fixture in radians unnamed)
MIXUP_GAIN = 0.7
#: where the given fit is beyond its bounds, undoing the mix-up must fit at least this much better (not a near tie
#: of a nearly symmetric change that lands inside the bounds): the trial's reversed joint 2 fits 0.53 times
TIE_GAIN = 0.95
#: mix-ups identified in full after the quick screen (the best by its rms)
SCREENED = 2
#: residual evaluations per free parameter of the quick fits that screen mix-ups (a plausible fit converges in
#: tens; a hopeless one had taken thousands, 6 s of a refused calibration)
QUICK_NFEV = 10
#: instrument points whose nominal model, base and tool registered, misses them by more than this rms [mm] have
#: their joint columns checked (the real data sets' nominal models: 0.8-3 mm; a reversed joint: 17-770 mm); an
#: undoing must bring it under this and to at most :data:`SCREEN_GAIN` of the rms as given
NOMINAL_GROSS_MM = 10.0
SCREEN_GAIN = 0.2
#: :data:`NOMINAL_GROSS_MM` of socket readings, whose nominal spread about each socket includes the arm's whole
#: uncalibrated error (the public Panda readings: up to 10.7 mm as recorded)
SOCKET_GROSS_MM = 25.0
#: undoings whose nominal misfit is within this factor and this many mm of the best are alike: the first in
#: :func:`_column_trials`' order is named, the others beside it (a UR's q2 off by 180 deg and its joint 1 negated fit
#: its tracker points alike, 0.77 mm; a wrist's q5 negated and q4 + 180 deg too)
TIE_FACTOR, TIE_MM = 1.05, 0.05
#: base-and-tool registrations of the screen (to 0.01 mm; the first ones decide between mm and hundreds of mm)
SCREEN_ITERATIONS = 15


def find_mixup(robot, res, q_rad: np.ndarray, positions: np.ndarray, fit_joints: Callable, fit_positions: Callable,
               material: bool = True, extra: tuple = (), suspect: bool = False) -> Mixup | None:
    """The mix-up whose undoing fits the campaign plausibly (the best), or None. ``res``: the identification as
    given; ``q_rad`` (N, n) its joint readings; ``positions`` (N,) its position labels; ``fit_joints(q_rad, full)``
    and ``fit_positions(positions, full)``: the same identification with other readings or labels, a quick one
    (``full`` False: one pass, no residual test) to screen every mix-up and the full one to confirm the best.
    Tried only when ``res`` has parameters beyond their bounds or residuals the noise model does not explain by a
    material margin (a swap of two nearby positions leaves 0.11 mm rms, not gross); with ``material`` False (a
    diagnosis, where physics left out makes the residuals material) only beyond bounds or gross
    (:func:`~calibrate.trust.gross`). ``extra``: further (:class:`Mixup`, ``run(full)``) trials (a campaign's
    fixture angles read as radians); ``fit_joints`` / ``fit_positions`` None: those trials left out. ``suspect``:
    tried whatever the residual test says (a test passed only at an implausible noise, a diagnosis with nothing
    found)."""
    test = res.residual_check
    beyond = bool(bound_warnings(robot, res))
    refused = suspect or test is None or (test.material if material else gross(test.birge, res.rms_mm))
    if not beyond and not refused:
        return None
    limit = res.rms_mm * (TIE_GAIN if beyond else MIXUP_GAIN)
    trials = list(extra)
    if fit_joints is not None:
        trials += [(what, lambda full, q=q: fit_joints(q, full)) for what, q in _sign_and_order_trials(robot.n, q_rad)]
    if fit_positions is not None:
        labels = sorted({int(p) for p in np.asarray(positions)})
        trials += [(Mixup(None, (a, b), 0.0, 0.0), lambda full, a=a, b=b: fit_positions(_swapped(positions, a, b),
                                                                                          full))
                   for a, b in itertools.combinations(labels, 2)]
    screened = [(what, run, _attempt(run, False, what)) for what, run in trials]
    # the quick fit leaves the rod's deflection uncompensated (0.2 mm for the trial's joint 2, 7 um in full): the
    # two it fits best are identified in full and judged
    ranked = sorted((t.rms_mm, i) for i, (_, _, t) in enumerate(screened) if t is not None)
    for _, i in ranked[:SCREENED]:
        what, run, _ = screened[i]
        trial = _attempt(run, True, what)
        if _fits(robot, trial, limit):
            return replace(what, rms_mm=float(trial.rms_mm), rms_given_mm=float(res.rms_mm))
    return None


#: a mix-up undone must leave less than this rms [mm]: what still misses by millimetres is no file mixed up (a
#: device trial: a column in cm had been named as two exchanged columns fitting to 3.4 mm)
UNDONE_RMS_MAX_MM = 1.0


def _fits(robot, trial, limit: float) -> bool:
    return (trial is not None and trial.success and trial.rms_mm <= min(limit, UNDONE_RMS_MAX_MM)
            and not bound_warnings(robot, trial))


def _attempt(run: Callable, full: bool, what: Mixup):
    try:
        trial = run(full)
    except CalibrationError as e:
        log.debug("%s: the identification was refused (%s)", what.label, e)
        return None
    log.debug("%s (%s): rms %.4g mm", what.label, "full" if full else "quick", trial.rms_mm)
    return trial


def _negated(q: np.ndarray, k: int) -> np.ndarray:
    q = np.array(q, float, copy=True)
    q[:, k] = -q[:, k]
    return q


def _exchanged(q: np.ndarray, a: int, b: int) -> np.ndarray:
    q = np.array(q, float, copy=True)
    q[:, [a, b]] = q[:, [b, a]]
    return q


def _reading_trials(camp, fit_readings: Callable) -> tuple:
    """(:class:`Mixup`, ``run(full)``) of each pair of the campaign's reading columns exchanged and of each column
    negated (a mirrored reading frame: no clamping pose turns it into the device's); for raw sensor readings, each
    sensor reversed (:func:`_sensor_trials`)."""
    if camp.raw:
        return _sensor_trials(camp, fit_readings)

    def run(cols: tuple):
        x = np.array(camp.x_D_mm, float, copy=True)
        if len(cols) == 1:
            x[:, cols[0]] = -x[:, cols[0]]
        else:
            x[:, list(cols)] = x[:, list(cols[::-1])]
        return lambda full: fit_readings(x, full)
    choices = [*itertools.combinations(range(3), 2), (0,), (1,), (2,)]
    return tuple((Mixup(None, None, 0.0, 0.0, readings=c), run(c)) for c in choices)


def _sensor_trials(camp, fit_readings: Callable) -> tuple:
    """(:class:`Mixup`, ``run(full)``) of each raw sensor reading reversed, mirrored about its zero (a device trial:
    sensor 2 mounted the other way round had been called unexplained), and of each pair of sensor columns
    exchanged. The device's map ``s = A x + zero`` is
    recovered from the campaign's readings and their converted ball centres (exact: the conversion is linear)."""
    if camp.x_D_mm is None or camp.readings_mm is None or camp.n < 4:
        return ()
    M = np.column_stack([camp.x_D_mm, np.ones(camp.n)])
    coef, *_ = np.linalg.lstsq(M, camp.readings_mm, rcond=None)
    A, zero = coef[:3].T, coef[3]
    if not abs(np.linalg.det(A)) > 1e-9:
        return ()

    def run(k: int):
        d = camp.readings_mm - zero
        d[:, k] = -d[:, k]
        x = np.linalg.solve(A, d.T).T
        return lambda full: fit_readings(x, full)

    def swap(a: int, b: int):                  # a device trial: s1 and s2 exchanged had been a device zero
        s = np.array(camp.readings_mm, float, copy=True)
        s[:, [a, b]] = s[:, [b, a]]
        x = np.linalg.solve(A, (s - zero).T).T
        return lambda full: fit_readings(x, full)
    reversed_ = [(Mixup(None, None, 0.0, 0.0, sensor=(k + 1, round(float(zero[k]), 4))), run(k)) for k in range(3)]
    exchanged = [(Mixup(None, None, 0.0, 0.0, sensors_exchanged=(a + 1, b + 1)), swap(a, b))
                 for a, b in itertools.combinations(range(3), 2)]
    return tuple(reversed_ + exchanged)


def _swapped(positions: np.ndarray, a: int, b: int) -> np.ndarray:
    p = np.asarray(positions)
    return np.where(p == a, b, np.where(p == b, a, p))


def campaign_mixup(robot, res, camp, fixture, rod_file, obs, rod, compensations, options, material: bool = True,
                   suspect: bool = False) -> Mixup | None:
    """:func:`find_mixup` for a MultiCal campaign: ``res`` its identification from ``obs`` (the observations of
    ``camp`` with ``fixture`` and the compliance file ``rod_file``) with the rod ``rod``, ``compensations`` and the
    :class:`~calibrate.estimate.FitOptions` ``options``; the screen runs one pass with :data:`QUICK_NFEV`;
    ``material`` and ``suspect`` as :func:`find_mixup`'s. A fixture file whose angles could be radians
    (:func:`_angles_could_be_radians`) is tried read as radians where no other mix-up is found, with residuals
    material enough also in a diagnosis."""
    quick = replace(options, max_compensation=1, expected_noise_mm=None, max_nfev_per_parameter=QUICK_NFEV)

    def fit(o, full):
        return identify(robot, o, rod, compensations, options if full else quick)

    def relabelled(positions, full):
        return fit(campaign_observations(replace(camp, position=positions), fixture, rod_file), full)
    # the joint columns first by the nominal model's misfit (cheap: every convention, not only signs and order)
    found = _column_mixup(robot, obs.q_rad, lambda q: _registered(robot, rod_file.tool_mm, replace(obs, q_rad=q)),
                          lambda q: fit(replace(obs, q_rad=q), True), NOMINAL_GROSS_MM, np.pi / 2)
    if found is None:
        reread = _reading_trials(camp, lambda x, full: fit(campaign_observations(replace(camp, x_D_mm=x), fixture,
                                                                                 rod_file), full))
        found = find_mixup(robot, res, obs.q_rad, camp.position, lambda q, full: fit(replace(obs, q_rad=q), full),
                           relabelled, material, reread, suspect)
    if found is None and _angles_could_be_radians(fixture):
        # residuals material suffice here also in a diagnosis: read as radians, small angles become large turns,
        # which no campaign of another physics fits better
        found = find_mixup(robot, res, obs.q_rad, camp.position, None, None, True, (
            (Mixup(None, None, 0.0, 0.0, fixture_radians=True),
             lambda full: fit(campaign_observations(camp, _degrees_from_radians(fixture), rod_file), full)),))
    elif found is None and (single := _positions_could_be_radians(fixture)):
        # one position's clamping written in radians among degrees (a device trial: named as outliers and a zero
        # shift at that position)
        found = find_mixup(robot, res, obs.q_rad, camp.position, None, None, True, tuple(
            (Mixup(None, None, 0.0, 0.0, fixture_radians=True, radians_position=j),
             lambda full, j=j: fit(campaign_observations(camp, _degrees_from_radians(fixture, j), rod_file), full))
            for j in single))
    return found


def _positions_could_be_radians(fixture) -> list:
    """The positions whose a, b, c are all within +-pi with one beyond 0.05 (a clamping turned by radians' worth)
    where the others' are not all so: one position's angles written in radians among degrees."""
    within = {j: np.all(np.abs(np.asarray(p, float)[3:]) <= np.pi + 1e-3) and np.any(np.abs(np.asarray(p, float)[3:])
                                                                                    > 0.05)
              for j, p in fixture.poses.items()}
    if all(within.values()) or len(within) < 3:
        return []
    return [j for j, w in within.items() if w]


def _angles_could_be_radians(fixture) -> bool:
    """Every clamping pose's a, b, c within +-pi and some of them off zero: a file the reader could have been given
    in radians (a fixture's clampings turn by tens of degrees between positions)."""
    angles = np.array([np.asarray(p, float)[3:] for p in fixture.poses.values()])
    return bool(np.all(np.abs(angles) <= np.pi + 1e-3) and np.any(np.abs(angles) > 1e-3))


def _degrees_from_radians(fixture, position=None):
    """``fixture`` with its angles (and their covariance) read as radians, in degrees: every position's, or
    ``position``'s alone."""
    k = np.r_[np.ones(3), np.full(3, np.degrees(1.0))]
    turn = [j for j in fixture.poses if position is None or j == position]
    poses = {j: np.asarray(p, float) * (k if j in turn else 1.0) for j, p in fixture.poses.items()}
    cov = None if fixture.pose_cov is None else {j: c * (np.outer(k, k) if j in turn else 1.0)
                                                 for j, c in fixture.pose_cov.items()}
    return replace(fixture, poses=poses, pose_cov=cov)


def points_mixup(robot, pts, identify_points_as: Callable) -> Mixup | None:
    """A joint of the instrument points ``pts`` (:class:`~calibrate.campaign.PointSet`) whose readings run the other
    way than ``robot``'s, or two joint columns exchanged, or a target changed part-way through the file
    (:func:`~calibrate.target_change.target_change`), or None: checked only when the nominal model, base and
    tool registered from scratch, misses the points by more than :data:`NOMINAL_GROSS_MM` rms; the negation or
    exchange that brings that under it (the best one) is confirmed by ``identify_points_as(points)``, the
    identification the command runs: it must converge with every parameter within its bounds. ``rms_given_mm`` is
    the registered nominal model's rms."""
    given = _points_misfit(robot, pts)
    found = _column_mixup(robot, pts.q_deg, lambda q: _registered_rms(robot, pts, q),
                          lambda q: identify_points_as(replace(pts, q_deg=q)), NOMINAL_GROSS_MM, 90.0, given)
    if found is None:                      # no column explains it: a target changed part-way through the file?
        found = target_change(pts, lambda part: _points_misfit(robot, part), given, NOMINAL_GROSS_MM, SCREEN_GAIN)
    return found


def _points_misfit(robot, pts) -> float:
    """The registered nominal misfit [mm] of instrument points as given (infinite where it cannot be computed)."""
    return _finite_misfit(lambda q: _registered_rms(robot, pts, q), pts.q_deg)


def sockets_mixup(robot, readings, identify_sockets_as: Callable) -> Mixup | None:
    """:func:`points_mixup` for ball-in-socket (or ball-bar) readings
    (:class:`~calibrate.sockets.SocketReadings`): the nominal model's spread about each socket's centre
    (:func:`~calibrate.socket_check.check_sockets`, rms [mm]) decides, ``identify_sockets_as(readings)`` (a
    :class:`~calibrate.result.CalibrationResult`) confirms, with :data:`SOCKET_GROSS_MM` for
    :data:`NOMINAL_GROSS_MM`: the public Panda, iiwa and Gen3 lite readings spread by 0.8-10.7 mm about their
    sockets as recorded (an uncalibrated arm's nominal model), a reversed joint by 135-550 mm."""
    def spread(q):
        r = replace(readings, q_rad=q)
        return check_sockets(robot, socket_start(robot, r), r).spread_rms_mm
    return _column_mixup(robot, readings.q_rad, spread, lambda q: identify_sockets_as(replace(readings, q_rad=q)),
                         SOCKET_GROSS_MM, np.pi / 2)


def _sign_and_order_trials(n: int, q: np.ndarray, **fields) -> list:
    """(:class:`Mixup`, the readings ``q`` (N, n) with it undone) of each joint negated, then each pair of columns
    exchanged; ``fields``: further :class:`Mixup` fields."""
    trials = [(Mixup(k + 1, None, 0.0, 0.0, **fields), _negated(q, k)) for k in range(n)]
    return trials + [(Mixup(None, None, 0.0, 0.0, columns=(a + 1, b + 1), **fields), _exchanged(q, a, b))
                     for a, b in itertools.combinations(range(n), 2)]


def _column_trials(n: int, q: np.ndarray, quarter: float) -> list:
    """(:class:`Mixup`, the readings with it undone) of each joint negated, each pair of columns exchanged, each
    joint's zero off by +-90 or 180 deg, and each joint read against the one before it (``q`` in units whose quarter
    turn is ``quarter``: 90 for degrees, pi/2 for radians), the likeliest first: undoings the readings cannot tell
    apart (a spherical wrist's q5 negated and q4 + 180 deg put a TCP on joint 6's axis alike) are named in this
    order."""
    m = dict(rms_mm=0.0, rms_given_mm=0.0, given_is_nominal=True)
    trials = _sign_and_order_trials(n, q, given_is_nominal=True)
    for k, turns in itertools.product(range(n), (1, -1, 2)):
        shifted = np.array(q, float, copy=True)
        shifted[:, k] += turns * quarter
        trials.append((Mixup(None, None, zero_offset=(k + 1, 90 * turns), **m), shifted))
    for k, sign in itertools.product(range(1, n), (1, -1)):
        coupled = np.array(q, float, copy=True)
        coupled[:, k] += sign * q[:, k - 1]
        trials.append((Mixup(None, None, coupling=(k, k + 1, sign), **m), coupled))
    return trials


def _column_mixup(robot, q: np.ndarray, misfit: Callable, identify_as: Callable, gross_mm: float,
                  quarter: float, given: float | None = None) -> Mixup | None:
    """The joint negation, column exchange, zero offset or coupling of the joint readings ``q`` (N, n;
    :func:`_column_trials`) that brings the nominal model's ``misfit(q)`` [mm] from beyond ``gross_mm`` to under it
    and :data:`SCREEN_GAIN` of the given, confirmed by ``identify_as(q)`` (converged, every parameter within its
    bounds); None otherwise (also where a trial cannot be computed: its misfit counts as infinite, its identification
    as refused); ``given``: ``misfit(q)`` when the caller has it already."""
    given = _finite_misfit(misfit, q) if given is None else given
    if not gross_mm < given < np.inf:
        return None
    trials = _column_trials(robot.n, q, quarter)
    misfits = np.array([_finite_misfit(misfit, qt) for _, qt in trials])
    near = np.nonzero(misfits <= TIE_FACTOR * misfits.min() + TIE_MM)[0]
    i = int(near[0])                                  # of undoings alike, the likeliest: the trials' order
    rms, (what, fixed) = float(misfits[i]), trials[i]
    tied = [trials[j][0].label for j in near[1:]]
    log.info("joint readings: nominal misfit %.1f mm as given, %.1f mm with %s", given, rms, what.label)
    if rms > min(gross_mm, SCREEN_GAIN * given):
        return None
    try:
        trial = identify_as(fixed)
    except (CalibrationError, ValueError, np.linalg.LinAlgError) as e:
        log.info("readings with %s: the identification was refused (%s)", what.label, e)
        return None
    if not (trial.success and not bound_warnings(robot, trial)):
        return None
    return replace(what, rms_mm=float(trial.rms_mm), rms_given_mm=given, alternatives=tuple(tied))


def _finite_misfit(misfit: Callable, q: np.ndarray) -> float:
    """``misfit(q)`` [mm], infinite where it cannot be computed or is not finite."""
    try:
        v = float(misfit(q))
    except (CalibrationError, ValueError, np.linalg.LinAlgError):
        return np.inf
    return v if np.isfinite(v) else np.inf


def refuse_mixed_up_joints(robot, readings, path, noise_mm: float | None = None, done: str = "calibrated",
                           checked: bool = False, hint: str = "") -> Mixup | None:
    """Raise :class:`CalibrationError` naming the file ``path`` and the column(s) when the joint readings of
    instrument points (a :class:`~calibrate.campaign.PointSet`, :func:`points_mixup`, confirmed by
    :func:`~calibrate.points.identify_points` with ``noise_mm``) or socket readings (a
    :class:`~calibrate.sockets.SocketReadings`, :func:`sockets_mixup`) are mixed up against ``robot``'s joints
    (a reversed joint, two columns exchanged, another zero or a coupled convention): their identification would
    take minutes to end in a mirrored chain or parameters far beyond their bounds. ``done``: what the command would
    have done (the message's "nothing was ..."); ``hint``: appended to the message (how to go on regardless).
    With ``checked`` (the user states the columns are right) the mix-up is returned instead (None: none found)."""
    if isinstance(readings, SocketReadings):
        mixup = sockets_mixup(robot, readings, lambda r: identify_sockets(robot, r, fix_unidentifiable=True).result)
    else:
        mixup = points_mixup(robot, readings, lambda p: identify_points(robot, p, noise_mm, fix_unidentifiable=True))
    if mixup is not None and not checked:             # the hint is about the joint columns: not a target's change
        tail = hint if mixup.target_change is None else ""
        raise CalibrationError(f"{mixup.reason()}; nothing was {done}{tail}", path=path, key=mixup.column_key)
    return mixup


def _registered_rms(robot, pts, q_deg: np.ndarray) -> float:
    """rms distance [mm] of the points from the nominal model with base and tool registered from scratch."""
    return _registered(robot, pts.tool_mm, replace(points_observations(pts), q_rad=np.deg2rad(q_deg)))


def _registered(robot, tool_mm, obs) -> float:
    """rms distance [mm] of the observations' ball centres in {W} from the nominal model (the tool ``tool_mm`` to
    start from) with base and tool registered from scratch (:data:`SCREEN_ITERATIONS`, to 0.01 mm)."""
    return register_base_and_tool(robot, ModelParams.nominal(robot, tool_mm), obs, SCREEN_ITERATIONS, 0.01)[2]
