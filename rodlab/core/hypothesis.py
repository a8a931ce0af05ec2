"""A diagnosis hypothesis: one effect at one place as columns linear in its parameters, and the parameter
schema effects share between their simulator, their hypothesis and the diagnosis report.

Domain packages build hypotheses from their effects (:mod:`rodlab.stiffness_rig.effects`); the application's
diagnosers select among them. The columns multiply *internal* parameters (the units the physics is computed
in); ``report_scale`` and ``report_offset`` turn a fitted internal value into the reported one, named as in the
schema: ``reported = report_offset + report_scale * internal``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import did_you_mean

__all__ = ["ParamSpec", "Hypothesis", "EffectSchema", "location_parts"]


@dataclass(frozen=True)
class ParamSpec:
    """One parameter of an effect, as the simulator takes it and the diagnosis reports it.

    name : the key in effect parameters, simulator input and diagnosis report (e.g. ``s_bend_rad_per_Nm``)
    unit : its unit as printed (``-`` for dimensionless)
    doc : one sentence of meaning
    default : the value ``rodlab rig simulate --effect NAME`` uses when none is given (a typical magnitude);
        ``None``: not set by default (optional)
    kind : ``float`` (a number), ``int`` (a whole number >= 1: a joint, a position, a count), ``str`` (a choice
        among ``choices``) or ``vector`` (3 numbers)
    choices : allowed values of a ``str`` parameter
    magnitude : a ``float`` that sizes the effect (when none is given, the effect's example sizes it); False for
        a setting such as creep's time constant
    """

    name: str
    unit: str
    doc: str
    default: object = None
    kind: str = "float"
    choices: tuple = ()
    magnitude: bool = True

    def __post_init__(self) -> None:
        if self.kind not in ("float", "int", "str", "vector"):
            raise ValueError(f"ParamSpec {self.name}: kind must be float, int, str or vector, got {self.kind!r}")

    def parse(self, value):
        """The value of this parameter from its text or number; :class:`ValueError` saying what is expected."""
        if self.kind == "str":
            v = str(value).strip()
            if self.choices and v not in self.choices:
                raise ValueError(f"{self.name} must be one of {list(self.choices)}, got {v!r}."
                                 + did_you_mean(v, self.choices))
            return v
        if self.kind == "vector":
            parts = value.split(",") if isinstance(value, str) else list(value)
            try:
                vec = [float(x) for x in parts]
            except (TypeError, ValueError):
                vec = []
            if len(vec) != 3 or not np.all(np.isfinite(vec)):
                raise ValueError(f"{self.name} must be 3 finite numbers [{self.unit}], got {value!r}")
            if self.unit == "-" and np.linalg.norm(vec) < 1e-9:
                raise ValueError(f"{self.name} is a direction: it must not be zero, got {value!r}")
            return vec
        if self.kind == "int":
            try:
                v = float(value)
            except (TypeError, ValueError):
                v = float("nan")
            if not (np.isfinite(v) and v == int(v) and v >= 1):
                raise ValueError(f"{self.name} must be a whole number >= 1, got {value!r}")
            return int(v)
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{self.name} must be a number [{self.unit}], got {value!r}") from None
        if not np.isfinite(v):
            raise ValueError(f"{self.name} must be a finite number [{self.unit}], got {value!r}")
        return v


@dataclass
class Hypothesis:
    """One candidate explanation: an effect at a location, as columns linear in its internal parameters.

    effect : the effect ID (a ``RigEffect`` / ``CampaignEffect`` value)
    location : the contract's location key (``ring_1``, ``sensor:z``, ``time``, ...) or None
    names : reported parameter names, one per column (the schema's names)
    X : shape=(n_samples, k), the change of each reading per unit internal parameter
    lower, upper : shape=(k,), physical bounds of the internal parameters
    explanation : the sentence of physics printed with a finding
    dC : structural effects: the C_F increment [mm/N] per unit internal parameter, one per column, else None
    hidden : parameters chosen from a grid rather than fitted linearly (counted in the BIC), or parameters of
        cost alone that make a hypothesis dearer in the BIC than a rival that fits about as well (a gauge's gain,
        outside the vocabulary)
    settings : those hidden parameters' values in report units (creep's ``tau_s``), reported beside the fit
    form_unresolved : the data do not pin this form down (a periodic error over less than one period fits any
        smooth error of its joint): a rival form at the same place that fits as well (delta BIC within 2) goes first
    report_scale, report_offset : shape=(k,), ``reported = report_offset + report_scale * internal``
    defers_to : the effect of a commoner rival at the same location that goes first unless this hypothesis fits
        clearly better, not merely as well with fewer parameters (a joint's zero shifted at one clamping position
        defers to that position's fixture pose), or None
    profile : {name: (low, high)} 95 % intervals over the hidden parameters' profile likelihood: internal units for
        a column's name (they widen its interval given the settings), report units for a setting (its interval)
    """

    effect: str
    location: str | None
    names: list
    X: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    explanation: str
    dC: list | None = None
    hidden: int = 0
    settings: dict = field(default_factory=dict)
    form_unresolved: bool = False
    report_scale: np.ndarray | None = None
    report_offset: np.ndarray | None = None
    defers_to: str | None = None
    profile: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.effect = str(self.effect)                 # the contract spelling (Enums print as their value)
        self.X = np.asarray(self.X, float)
        if self.X.ndim != 2:
            raise ValueError(f"hypothesis {self.effect}: X must be (n_samples, k), got shape {self.X.shape}")
        k = self.X.shape[1]
        self.lower = np.asarray(self.lower, float).reshape(-1)
        self.upper = np.asarray(self.upper, float).reshape(-1)
        if len(self.names) != k or self.lower.shape != (k,) or self.upper.shape != (k,):
            raise ValueError(f"hypothesis {self.effect}: {k} columns need {k} names and bounds, got "
                             f"{len(self.names)} names, bounds {self.lower.shape}, {self.upper.shape}")
        self.report_scale = np.ones(k) if self.report_scale is None else np.asarray(self.report_scale, float)
        self.report_offset = np.zeros(k) if self.report_offset is None else np.asarray(self.report_offset, float)

    @property
    def n_params(self) -> int:
        """Parameters counted in the BIC: the columns plus the hidden ones."""
        return self.X.shape[1] + self.hidden

    @property
    def label(self) -> str:
        """``effect at location`` with its settings, as alternatives are named."""
        out = self.effect + (f" at {self.location}" if self.location else "")
        if self.settings:
            out += " (" + ", ".join(f"{k} {v:g}" for k, v in self.settings.items()) + ")"
        return out

    def reported(self, internal: np.ndarray, se: np.ndarray) -> tuple[dict, dict]:
        """({name: value}, {name: [low, high]} 95 % intervals) in report units, settings included."""
        params, intervals = {}, {}
        for name, v, s, a, b in zip(self.names, internal, se, self.report_scale, self.report_offset):
            lo, hi = v - 1.96 * s, v + 1.96 * s
            if name in self.profile:                   # the hidden parameters' uncertainty too
                lo, hi = min(lo, self.profile[name][0]), max(hi, self.profile[name][1])
            params[name] = float(b + a * v)
            intervals[name] = sorted([float(b + a * lo), float(b + a * hi)])
        params.update({k: float(v) for k, v in self.settings.items()})
        intervals.update({k: sorted(float(x) for x in self.profile[k]) for k in self.settings if k in self.profile})
        return params, intervals


def location_parts(location: str | None) -> tuple[str, str]:
    """A location key split into its kind and its value: ``position:3`` -> (``position``, ``3``),
    ``points:2.4,5.1`` -> (``points``, ``2.4,5.1``), ``time`` -> (``time``, ``""``)."""
    kind, _, value = str(location or "").partition(":")
    return kind, value


class EffectSchema:
    """The parameter schema of one effect: its parameters (:class:`ParamSpec`), the example magnitude used when
    none is given, completion and checking of given parameters. Rig and campaign effects share it; each
    package's base class sets :meth:`fail` to raise its own error."""

    effect: str = ""
    params: tuple = ()
    example: dict = {}

    def fail(self, message: str, key: str) -> None:
        """Raise the package's error for parameter ``key`` of this effect."""
        raise ValueError(message)

    def spec(self, name: str) -> ParamSpec:
        for p in self.params:
            if p.name == name:
                return p
        names = [p.name for p in self.params]
        self.fail(f"effect {self.effect}: unknown parameter {name!r}; its parameters are {names}."
                  + did_you_mean(name, names), f"{self.effect}.{name}")

    def complete(self, given: dict) -> dict:
        """The full parameters from those ``given``: defaults filled in, the example magnitude when no number
        is given, every value checked (the package's error naming the effect and key)."""
        out = {p.name: p.default for p in self.params if p.default is not None}
        parsed = {}
        for k, v in dict(given).items():
            spec = self.spec(str(k))
            try:
                parsed[spec.name] = spec.parse(v)
            except ValueError as e:
                self.fail(str(e), f"{self.effect}.{spec.name}")
        if not any(self.spec(k).kind == "float" and self.spec(k).magnitude for k in parsed):
            out.update(self.example_for({**out, **parsed}))
        out.update(parsed)
        self.check(out)
        return out

    def example_for(self, p: dict) -> dict:
        """The example magnitude for parameters ``p`` that size nothing yet."""
        return dict(self.example)

    def check(self, p: dict) -> None:
        """Fail if the completed parameters ``p`` cannot be simulated."""

    def value(self, p: dict, name: str) -> float:
        return float(p.get(name, 0.0) or 0.0)

    def params_markdown(self) -> str:
        """The parameters as a docs table cell: names with units (choices for a setting)."""
        return ", ".join(f"`{p.name}` ({' / '.join(p.choices)})" if p.kind == "str" else f"`{p.name}` [{p.unit}]"
                         for p in self.params)
