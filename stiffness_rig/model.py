"""Physical model of the stiffness rig: what the gauges read while weights hang on the rod.

The rod responds with a true compliance ``C_true`` (the simulated one, possibly altered by a structural
effect); the rig adds its own physics. Effects (contract ``effects.md`` vocabulary, subject ``rig``):

=================== ==========================================================================
``friction``        Coulomb friction F_f [N] in the slides: the load reaching the rod is F - F_f while
                    loading, F + F_f while unloading (the hold's direction of travel)
``tare``            a dead load [kg] missing from ``mass_kg`` whenever the hanger is on
``creep``           Kelvin-Voigt creep: extra deflection phi * C F approached with time constant tau [s]
``nonlinearity``    load-dependent compliance C (1 + beta |F| / 10 N)
``crosstalk``       a gauge tilted by angle eps [rad]: it reads cos(eps) own + sin(eps) another axis
``drift``           zero drift: rate [mm/s] in time, or coefficient [mm/K] on temp_C
``compliance_scale`` C_true = r C_sim
``torsion_compliance`` extra torsion compliance s [rad/(N mm)] of pipe I
``joint_compliance`` a rotational spring at a point of the rod (bending s_b, torsion s_t [rad/(N mm)])
=================== ==========================================================================
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rodlab.enums import LoadAxis, Phase
from rodlab.units import G0

__all__ = ["LoadSchedule", "RigModel", "spring_compliance", "Hold"]


def spring_compliance(point_T_mm, axis, s_bend: float, s_torsion: float) -> np.ndarray:
    """Extra C_F [mm/N] of a rotational spring at ``point_T_mm`` (in {T}) on a member along unit ``axis``.

    A tip force F makes a moment (0 - point) x F about the spring; each compliant rotation axis e with
    compliance s adds ``s (e x (0 - point))(e x (0 - point))^T``, i.e. ``s a a^T`` with ``a = e x r``.
    """
    r = -np.asarray(point_T_mm, dtype=float)           # from the spring to the ball centre (origin of {T})
    t = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(t[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    b1 = np.cross(t, helper)
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(t, b1)
    C = np.zeros((3, 3))
    for e, s in ((b1, s_bend), (b2, s_bend), (t, s_torsion)):
        a = np.cross(e, r)
        C += s * np.outer(a, a)
    return C


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
        from .errors import RigError
        bad = [m for m in self.masses if not (np.isfinite(m) and m > 0)]
        if not self.masses or bad:
            raise RigError(f"masses must be positive numbers of kg, got {list(self.masses)}; give e.g. 0.5,1.0,1.5,2.0 "
                           f"(the mass-0 hold is always recorded)", key="masses")
        if list(self.masses) != sorted(self.masses):
            raise RigError(f"masses must increase (they are loaded one after the other), got {list(self.masses)}",
                           key="masses")
        checks = {"repeats": (self.repeats, "a whole number >= 1", self.repeats >= 1 and int(self.repeats) == self.repeats),
                  "hold_s": (self.hold_s, "a duration > 0 s", np.isfinite(self.hold_s) and self.hold_s > 0),
                  "rate_Hz": (self.rate_Hz, "a rate > 0 Hz", np.isfinite(self.rate_Hz) and self.rate_Hz > 0),
                  "gap_s": (self.gap_s, "a duration >= 0 s", np.isfinite(self.gap_s) and self.gap_s >= 0)}
        for key, (value, expected, ok) in checks.items():
            if not ok:
                raise RigError(f"{key} must be {expected}, got {value!r}", key=key)
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

    C_sim : simulated C_F [mm/N]; effects : {effect id: parameters}; noise_mm : per-reading SD;
    resolution_mm : gauge resolution (0 = none); seed : random seed; T0_C, temp_amplitude_K, temp_period_s :
    the room temperature cycle.
    """

    C_sim: np.ndarray
    effects: dict = field(default_factory=dict)
    noise_mm: float = 0.0006
    resolution_mm: float = 0.001
    seed: int = 0
    T0_C: float = 21.0
    temp_amplitude_K: float = 1.0
    temp_period_s: float = 1800.0
    rod_points: dict = field(default_factory=dict)   # joint name -> (point_T_mm, axis)

    def __post_init__(self) -> None:
        from .errors import RigError
        if not (np.isfinite(self.noise_mm) and self.noise_mm >= 0):
            raise RigError(f"the per-reading noise must be >= 0 mm, got {self.noise_mm!r} (--noise-um takes um, "
                           f"e.g. 0.6)", key="noise")
        self.rng = np.random.default_rng(self.seed)
        self._creep = np.zeros(3)
        self._t_last = None
        self._F_last = np.zeros(3)

    @property
    def C_true(self) -> np.ndarray:
        C = np.array(self.C_sim, dtype=float)
        e = self.effects
        if "compliance_scale" in e:
            C = C * float(e["compliance_scale"]["r"])
        if "torsion_compliance" in e:
            p = e["torsion_compliance"]
            C = C + spring_compliance(p.get("point_T_mm", [0, 0, 0]), p.get("axis", [0, 0, 1]), 0.0, float(p["s_rad_per_Nmm"]))
        if "joint_compliance" in e:
            p = e["joint_compliance"]
            C = C + spring_compliance(p["point_T_mm"], p["axis"], float(p["s_bend_rad_per_Nmm"]),
                                      float(p.get("s_torsion_rad_per_Nmm", 0.0)))
        return C

    def temperature(self, t: float) -> float:
        return self.T0_C + self.temp_amplitude_K * np.sin(2 * np.pi * t / self.temp_period_s)

    def force_on_rod(self, hold: Hold) -> np.ndarray:
        """Force on the ball in {T} [N] during ``hold`` (friction and tare included)."""
        e = self.effects
        m = hold.mass_kg
        if m > 0 and "tare" in e:
            m += float(e["tare"]["tare_kg"])
        F = m * G0
        if "friction" in e and (hold.mass_kg > 0 or hold.phase is Phase.UNLOAD):
            Ff = float(e["friction"]["F_f_N"])
            F = F - Ff if hold.phase is Phase.LOAD else F + Ff
        vec = np.zeros(3)
        vec[hold.axis.index] = hold.axis.sign * F
        return vec

    def reading(self, t: float, hold: Hold, measured=(0, 1, 2)) -> tuple:
        """Gauge readings (x, y, z) [mm] at time ``t`` (NaN for unmeasured) and the temperature [degC]."""
        e = self.effects
        F = self.force_on_rod(hold)
        C = self.C_true
        if "nonlinearity" in e:
            C = C * (1.0 + float(e["nonlinearity"]["beta"]) * np.linalg.norm(F) / 10.0)
        x = C @ F
        if "creep" in e:
            phi, tau = float(e["creep"]["phi"]), float(e["creep"]["tau_s"])
            target = phi * (C @ F)
            dt = 0.0 if self._t_last is None else max(t - self._t_last, 0.0)
            self._creep = target + (self._creep - target) * np.exp(-dt / tau)
            x = x + self._creep
        self._t_last = t
        if "crosstalk" in e:
            p = e["crosstalk"]
            i, j, eps = "xyz".index(p["sensor"]), "xyz".index(p["from"]), float(p["angle_rad"])
            xi = np.cos(eps) * x[i] + np.sin(eps) * x[j]
            x = x.copy()
            x[i] = xi
        temp = self.temperature(t)
        if "drift" in e:
            p = e["drift"]
            x = x + float(p.get("rate_mm_per_s", 0.0)) * t + float(p.get("mm_per_K", 0.0)) * (temp - self.T0_C)
        x = x + self.rng.normal(0.0, self.noise_mm, 3)
        if self.resolution_mm > 0:
            x = np.round(x / self.resolution_mm) * self.resolution_mm
        out = np.full(3, np.nan)
        out[list(measured)] = x[list(measured)]
        return out, float(np.round(temp, 2))
