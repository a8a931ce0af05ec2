"""Physical model of the stiffness rig: what the gauges read while weights hang on the rod.

The rod responds with a true compliance (the simulated one, possibly altered by a structural effect); the rig
adds its own physics. Every effect is one module of :mod:`rodlab.stiffness_rig.effects` (the registry
``RIG_EFFECTS`` lists them with their parameters and units); :class:`RigModel` applies their hooks in order.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rodlab.core.enums import LoadAxis, Phase
from rodlab.core.units import G0

from .effects import RIG_EFFECTS, RigState, complete_effects, spring_compliance
from .errors import RigError

__all__ = ["LoadSchedule", "RigModel", "spring_compliance", "Hold"]


#: more samples per hold than this is a unit slip, not a plan (a day's creep hold at 10 Hz is 864 000)
MAX_SAMPLES_PER_HOLD = 1e7
#: and more samples than this in a whole plan (~100 holds of a day's creep hold)
MAX_SAMPLES_PER_PLAN = 1e8


@dataclass
class LoadSchedule:
    """Load schedule of a stiffness test: per load axis a mass-0 hold, then ``repeats`` x (loading up the ``masses``, unloading
    back to 0); ``hold_s`` [s] sampled at ``rate_Hz``; ``gap_s`` [s] between holds (weights being moved).
    ``measured``: per load axis the two measured components (default: load axis + one perpendicular)."""

    axes: tuple = ("y", "z", "x")
    masses: tuple = (0.5, 1.0, 1.5, 2.0)
    repeats: int = 5
    hold_s: float = 8.0
    rate_Hz: float = 10.0
    gap_s: float = 4.0
    measured: dict = field(default_factory=lambda: {"x": (0, 2), "y": (1, 2), "z": (0, 2),
                                                   "-x": (0, 2), "-y": (1, 2), "-z": (0, 2)})

    def __post_init__(self) -> None:
        bad = [m for m in self.masses if not (np.isfinite(m) and m > 0)]
        if not self.masses or bad:
            raise RigError(f"masses must be positive numbers of kg, got {list(self.masses)}; give e.g. 0.5,1.0,1.5,2.0 "
                           f"(the mass-0 hold is always recorded)", key="masses")
        if list(self.masses) != sorted(self.masses):
            raise RigError(f"masses must increase (they are loaded one after the other), got {list(self.masses)}",
                           key="masses")
        r = self.repeats                                 # an int of any size, or a float that is whole
        whole = r >= 1 and (isinstance(r, (int, np.integer)) or (bool(np.isfinite(r)) and int(r) == r))
        checks = {"repeats": (self.repeats, "a whole number >= 1", whole),
                  "hold_s": (self.hold_s, "a duration > 0 s", np.isfinite(self.hold_s) and self.hold_s > 0),
                  "rate_Hz": (self.rate_Hz, "a rate > 0 Hz", np.isfinite(self.rate_Hz) and self.rate_Hz > 0),
                  "gap_s": (self.gap_s, "a duration >= 0 s", np.isfinite(self.gap_s) and self.gap_s >= 0)}
        for key, (value, expected, ok) in checks.items():
            if not ok:
                raise RigError(f"{key} must be {expected}, got {value!r}", key=key)
        per_hold = self.hold_s * self.rate_Hz
        holds = len(self.axes) * (1 + self.repeats * 2 * len(self.masses))     # :meth:`holds`, counted
        holds = float(holds) if holds < 1e300 else np.inf      # repeats = 1e308 (an int beyond any float: overflow)
        if not per_hold <= MAX_SAMPLES_PER_HOLD or not holds * per_hold <= MAX_SAMPLES_PER_PLAN:   # and not inf
            key = "rate_Hz" if self.rate_Hz > 1e3 else "repeats" if per_hold <= MAX_SAMPLES_PER_HOLD else "hold_s"
            count = f"{holds:.6g}" if holds < 1e300 else "more than 1e300"
            raise RigError(f"{count} holds of {self.hold_s:g} s at {self.rate_Hz:g} Hz take {holds * per_hold:.3g} "
                           f"samples ({per_hold:.3g} per hold), more than a plan's {MAX_SAMPLES_PER_PLAN:.0e} or a "
                           f"hold's {MAX_SAMPLES_PER_HOLD:.0e}: is hold_s in seconds, rate_Hz in Hz and repeats a "
                           f"count? (the paper: 8 s at 10 Hz, 5 repeats; a day's creep hold at 10 Hz is 864 000 "
                           f"samples)", key=key)
        if round(self.hold_s * self.rate_Hz) < 1:
            raise RigError(f"a hold of {self.hold_s:g} s at {self.rate_Hz:g} Hz takes no sample; give hold_s >= "
                           f"{1 / self.rate_Hz:g} s (one sample) or a higher rate, e.g. the paper's 8 s at 10 Hz",
                           key="hold_s")
        for ax in self.axes:
            LoadAxis.parse(ax, "load axis")

    def holds(self):
        """(axis, repeat, phase, mass) of every hold, in order."""
        out = []
        for ax in self.axes:
            axis = LoadAxis(ax)
            out.append((axis, 1, Phase.LOAD, 0.0))
            for rep in range(1, self.repeats + 1):
                for m in self.masses:
                    out.append((axis, rep, Phase.LOAD, float(m)))
                for m in list(self.masses[:-1])[::-1] + [0.0]:
                    out.append((axis, rep, Phase.UNLOAD, float(m)))
        return out


@dataclass
class Hold:
    """One hold being recorded: index, axis, repeat, phase, mass, start time."""

    step: int
    axis: LoadAxis
    repeat: int
    phase: Phase
    mass_kg: float
    t0: float


@dataclass
class RigModel:
    """The rod on the rig with its effects; ``reading(...)`` gives what the gauges show.

    C_sim : simulated C_F [mm/N], shape=(3, 3); effects : {effect ID: parameters} (names and units of
    :data:`~rodlab.stiffness_rig.effects.RIG_EFFECTS`; missing ones take their defaults); noise_mm : per-reading
    SD [mm]; resolution_mm : gauge resolution [mm] (0 = none); seed : random seed; T0_C, temp_amplitude_K,
    temp_period_s : the room temperature cycle [degC, K, s]; places : {location: (point in {T} [mm], member
    axis)} where joint springs can sit (:func:`~rodlab.stiffness_rig.effects.joint_places`); load_cell_noise_N :
    SD of a load cell's reading [N] between the loading frame and the rod (None: no load cell; 0: a perfect
    one), read by :meth:`load_cell` with its own random stream
    """

    C_sim: np.ndarray
    effects: dict = field(default_factory=dict)
    noise_mm: float = 0.0006
    resolution_mm: float = 0.001
    seed: int = 0
    T0_C: float = 21.0
    temp_amplitude_K: float = 1.0
    temp_period_s: float = 1800.0
    places: dict = field(default_factory=dict)
    load_cell_noise_N: float | None = None

    def __post_init__(self) -> None:
        if not (np.isfinite(self.noise_mm) and self.noise_mm >= 0):
            raise RigError(f"the per-reading noise must be >= 0 mm, got {self.noise_mm!r} (--noise-um takes um, "
                           f"e.g. 0.6)", key="noise")
        if self.load_cell_noise_N is not None and not (np.isfinite(self.load_cell_noise_N)
                                                       and self.load_cell_noise_N >= 0):
            raise RigError(f"the load cell's noise must be >= 0 N, got {self.load_cell_noise_N!r}",
                           key="load_cell_noise_N")
        self.rng_load_cell = np.random.default_rng([self.seed, 1])
        self.effects = complete_effects(self.effects)
        self._given = dict(self.effects)            # as completed, before a plan fills anything in
        self._active = [(RIG_EFFECTS[e], p) for e, p in self.effects.items()]
        self.rng = np.random.default_rng(self.seed)
        self.state = RigState()
        self.C_true = self._true_compliance()

    def with_plan(self, masses) -> None:
        """Fill in what the load plan sets in the effects' parameters (a hysteresis loop's top load), from the
        parameters as given (another plan's fill-ins are not kept)."""
        self.effects = {e: RIG_EFFECTS[e].with_plan(p, masses) for e, p in self._given.items()}
        self._active = [(RIG_EFFECTS[e], p) for e, p in self.effects.items()]

    def _true_compliance(self) -> np.ndarray:
        C = np.array(self.C_sim, dtype=float)
        for eff, p in self._active:
            C = eff.compliance(C, p, self.places)
        return C

    def reset_series(self) -> None:
        """The rod is remounted for a new series: no creep left."""
        self.state.creep = np.zeros((2, 3))
        self.state.creep_target = np.zeros((2, 3))
        self.state.gauge_contact = None

    def temperature(self, t: float) -> float:
        return self.T0_C + self.temp_amplitude_K * np.sin(2 * np.pi * t / self.temp_period_s)

    def axial_force(self, hold: Hold) -> float:
        """The load's magnitude [N] during ``hold``: the hung weight with friction and tare, what a load cell in
        the load's line carries."""
        m = hold.mass_kg
        for eff, p in self._active:
            m = eff.mass(m, hold, p)
        F = m * G0
        for eff, p in self._active:
            F = eff.force(F, hold, p)
        return F

    def force_on_rod(self, hold: Hold) -> np.ndarray:
        """Force on the ball in {T} [N] during ``hold`` (friction and tare included; along the load's line,
        which an effect may tilt off the hold's axis)."""
        vec = np.zeros(3)
        vec[hold.axis.index] = hold.axis.sign * self.axial_force(hold)
        for eff, p in self._active:
            vec = eff.load_line(vec, hold, p)
        return vec

    @property
    def has_load_cell(self) -> bool:
        return self.load_cell_noise_N is not None

    def load_cell(self, hold: Hold) -> float:
        """A load cell's reading [N]: the force the rod carries along the load's line (friction and tare
        included), with its noise, to 1 mN; NaN without a load cell."""
        if self.load_cell_noise_N is None:
            return float("nan")
        F = self.axial_force(hold)
        return round(F + float(self.rng_load_cell.normal(0.0, self.load_cell_noise_N)), 3)

    def reading(self, t: float, hold: Hold, measured=(0, 1, 2)) -> tuple:
        """Gauge readings (x, y, z) [mm] at time ``t`` (NaN for unmeasured) and the temperature [degC]."""
        F = self.force_on_rod(hold)
        C = self.C_true
        for eff, p in self._active:
            C = eff.load_compliance(C, F, hold, p)
        x = C @ F
        for eff, p in self._active:
            x = eff.deflection(x, C, F, t, self.state, p)
        self.state.t_last = t
        temp = self.temperature(t)
        for eff, p in self._active:
            x = eff.reading(x, t, temp - self.T0_C, p)
        x = x + self.rng.normal(0.0, self.noise_mm, 3)
        if self.resolution_mm > 0:
            x = np.round(x / self.resolution_mm) * self.resolution_mm
        out = np.full(3, np.nan)
        out[list(measured)] = x[list(measured)]
        return out, float(np.round(temp, 2))

    def zero_reading(self, t: float, hold: Hold) -> np.ndarray:
        """The noiseless, unquantised reading the gauges are zeroed on at the start of a series (the random
        stream is left where it was)."""
        saved = self.rng.bit_generator.state
        noise, self.noise_mm = self.noise_mm, 0.0
        res, self.resolution_mm = self.resolution_mm, 0.0
        try:
            return np.nan_to_num(self.reading(t, hold, (0, 1, 2))[0])
        finally:
            self.noise_mm, self.resolution_mm = noise, res
            self.rng.bit_generator.state = saved
