"""The estimation kernel every identification shares (campaign and instrument points in :mod:`.identify`, socket
readings in :mod:`.socket_fit`, pose planning in :mod:`.plan`):

- :class:`FitOptions`: how a fit is asked for (pins, frees, loss, periodic terms, noise level, start);
- :class:`Selection`: what the choice of the free parameters looks at (catalogue, tool, positions, pins, frees);
- :func:`check_names`: ``--pin`` / ``--free`` names against the parameter catalogue;
- :func:`pinned_vector`: the internal parameter vector at the start with the pinned values;
- :func:`select_free`: the parameters to fit: structural rules, the user's pins and frees, then a rank analysis
  of the column-normalised Jacobian in preference order (a column in the span of those kept is held and
  reported with the combination it belongs to);
- :func:`physical_bounds`: a joint compliance stays within [0, :data:`C_MAX`];
- :func:`solve`: one least-squares pass (MINPACK LM, bounded trust region only when needed);
- :func:`parameter_value`: a parameter's value in contract units.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rodlab.core.errors import did_you_mean
from rodlab.core.units import DEVICE_NOISE_MM

from .errors import CalibrationError
from .kinematics import HARMONICS, ModelParams
from .params import INTERNAL_SCALE, ParamInfo, structural_fixed

__all__ = ["FitOptions", "Selection", "C_MAX", "check_names", "pinned_vector", "select_free", "physical_bounds", "solve",
           "parameter_value", "data_name"]



@dataclass(frozen=True)
class FitOptions:
    """How an identification is asked to fit (the defaults are a planned MultiCal campaign's).

    pinned : {parameter name: value in contract units} held at that value
    freed : names of parameters the defaults hold that are fitted (e.g. ``fixture_2_x``, ``tool_y``)
    robust : soft-L1 loss (gross alignment errors lose weight)
    fix_unidentifiable : parameters the data cannot separate (beyond the structural rules) are held at their
        nominal values and reported, instead of refusing the data set: for instrument data that was not planned
        for this model (single-joint sweeps, few configurations); a planned campaign should not need it
    find_tool : start from a tool point found from the data (for instrument points whose tool is only roughly
        known)
    harmonics : joints (1-based) whose periodic angle errors (first and second harmonic of the joint reading,
        ``h1s_j .. h2c_j``) are identified too: gear or encoder eccentricity that ``rodlab diagnose`` named
    expected_noise_mm : the measuring noise per coordinate [mm] the residual test judges against; None skips it
    fixture_sigma : 1-sigma uncertainty of each clamping pose (position [mm], angle [deg])
    max_compensation : most identification / compensation passes
    max_nfev_per_parameter : most residual evaluations of one pass per free parameter (a quick screen of many
        candidate fits stops a hopeless one early)
    initial : the model to start from (:class:`~rodlab.calibrate.kinematics.ModelParams`), or None: nominal with
        the base registered to the points
    """

    pinned: dict = field(default_factory=dict)
    freed: frozenset = frozenset()
    robust: bool = False
    fix_unidentifiable: bool = False
    find_tool: bool = False
    harmonics: tuple = ()
    expected_noise_mm: float | None = DEVICE_NOISE_MM
    fixture_sigma: tuple = (0.01, 0.002)
    max_compensation: int = 6
    max_nfev_per_parameter: int = 200
    initial: ModelParams | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "pinned", {str(k): float(v) for k, v in dict(self.pinned or {}).items()})
        object.__setattr__(self, "freed", frozenset(self.freed or ()))
        object.__setattr__(self, "harmonics", tuple(self.harmonics or ()))
        if int(self.max_compensation) < 1:
            raise ValueError(f"max_compensation must be >= 1, got {self.max_compensation!r}")
        if int(self.max_nfev_per_parameter) < 1:
            raise ValueError(f"max_nfev_per_parameter must be >= 1, got {self.max_nfev_per_parameter!r}")


@dataclass(frozen=True)
class Selection:
    """What the choice of the free parameters (:func:`select_free`,
    :func:`~rodlab.calibrate.identify.free_parameters`) looks at.

    infos : the parameter catalogue (:func:`~rodlab.calibrate.params.catalogue`), in preference order
    tool_mm : the tool vector in {n} [mm], shape=(3,) (a tool on the last axis cannot show that axis' offset)
    positions : the clamping positions whose fixture offsets are in the catalogue (empty for instrument points)
    pinned : {name: value in contract units} the user holds; freed : names the defaults hold that are fitted
    fix_unidentifiable : hold what the data cannot separate at nominal (reported) instead of refusing the data
    """

    infos: list
    tool_mm: np.ndarray
    positions: tuple = ()
    pinned: dict = field(default_factory=dict)
    freed: frozenset = frozenset()
    fix_unidentifiable: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "positions", tuple(self.positions))
        object.__setattr__(self, "pinned", dict(self.pinned))
        object.__setattr__(self, "freed", frozenset(self.freed))

    @classmethod
    def of(cls, infos: list, tool_mm, positions, options: FitOptions) -> "Selection":
        """The selection an identification with ``options`` asks for."""
        return cls(infos, tool_mm, positions, options.pinned, options.freed, options.fix_unidentifiable)


def check_names(names: list, pinned: dict, freed: set) -> None:
    """Every pinned or freed name is a parameter of the catalogue ``names``; else a one-line error with the
    nearest name (or, for a periodic term, the option that adds it)."""
    for nm in list(pinned) + list(freed):
        if nm not in names:
            kind, _, j = nm.rpartition("_")
            hint = (f" It is a periodic joint error: add joint {j} to --joint-harmonics." if kind in HARMONICS
                    else did_you_mean(nm, names))
            raise CalibrationError(f"unknown parameter {nm!r}." + hint, key="parameters")


def pinned_vector(infos, start: ModelParams, pinned: dict) -> np.ndarray:
    """The internal parameter vector: zero (the start) except the pinned values."""
    names = [i.name for i in infos]
    x = np.zeros(len(infos))
    for nm, v in pinned.items():
        k = names.index(nm)
        if infos[k].kind == "c" and not 0.0 <= v <= C_MAX:      # a trial: -3.2e-5 had become 0 without a word
            unit = (f"; the value is in rad/(N m): {v:g} urad/(N m) is {v * 1e-6:g}" if v >= 1 and v * 1e-6 <= C_MAX
                    else "; a negative one is a sag of the wrong sign: check the sign of the measured points' "
                         "columns or an axis direction" if v < 0 else "")
            raise CalibrationError(f"--pin {nm}={v:g}: a joint compliance lies in [0, {C_MAX:g}] rad/(N m), the "
                                   f"range the identification keeps it in{unit}", key=nm)
        x[k] = (v - parameter_value(start, infos[k], 0.0)) * INTERNAL_SCALE[infos[k].unit] if infos[k].kind in (
            "base_t", "base_r", "tool") else v * INTERNAL_SCALE[infos[k].unit]
    return x


def select_free(robot, sel: Selection, J0: np.ndarray, tol: float = 1e-7) -> tuple[list, dict]:
    """Free parameters (indices into ``sel.infos``) and why the others are held: structural rules, user pins /
    frees, then the preference-ordered rank analysis of the Jacobian ``J0`` (..., P)."""
    infos, pinned, freed, positions = sel.infos, sel.pinned, sel.freed, sel.positions
    fixed = structural_fixed(robot, sel.tool_mm, positions)
    if "tool_y" in freed and f"dtheta_{robot.n}" not in freed:
        fixed[f"dtheta_{robot.n}"] = "combined with the tool point's azimuth about the last axis (tool_x, tool_y)"
    for name in freed:
        fixed.pop(name, None)
    for name in pinned:
        fixed[name] = "pinned by the user"
    A = J0.reshape(-1, J0.shape[-1])
    norms = np.linalg.norm(A, axis=0)
    kept: list[int] = []
    Q = np.zeros((A.shape[0], 0))
    reasons = dict(fixed)
    for k, info in enumerate(infos):
        if info.name in fixed:
            continue
        if norms[k] < 1e-12:
            reasons[info.name] = "has no effect on the measured points"
            continue
        v = A[:, k] / norms[k]
        r = v - Q @ (Q.T @ v)
        if np.linalg.norm(r) < np.sqrt(tol) * 10 and info.name not in freed:
            coef, *_ = np.linalg.lstsq(A[:, kept] / norms[kept], v, rcond=None)
            big = [infos[kept[m]].name for m in np.argsort(-np.abs(coef)) if abs(coef[m]) > 0.1][:4]
            reasons[info.name] = f"combined with {', '.join(big)} in this {data_name(positions)}"
            continue
        kept.append(k)
        Q = np.column_stack([Q, r / np.linalg.norm(r)])
    return kept, reasons


#: joint compliance a gearbox can have [rad/(N m)]: identified within [0, C_MAX] by construction (bounded LM)
C_MAX = 1e-4


def physical_bounds(infos, start: ModelParams) -> tuple[np.ndarray, np.ndarray]:
    """Bounds of the internal parameter vector: a joint compliance stays within [0, :data:`C_MAX`] (a negative
    compliance is not a gearbox); every other parameter is free."""
    lo = np.full(len(infos), -np.inf)
    hi = np.full(len(infos), np.inf)
    for k, info in enumerate(infos):
        if info.kind == "c":
            s = INTERNAL_SCALE[info.unit]
            lo[k] = (0.0 - start.c[info.index]) * s
            hi[k] = (C_MAX - start.c[info.index]) * s
    return lo, hi


def solve(fun, jac, z0: np.ndarray, bounds: tuple[np.ndarray, np.ndarray], robust: bool, f_scale: float, max_nfev: int):
    """One least-squares pass from ``z0`` within ``bounds`` = (lower, upper). Without a robust loss, MINPACK's
    Levenberg-Marquardt runs first (several times faster than the bounded trust-region solver); only if its
    solution leaves the physical bounds is the bounded problem solved, from the clipped solution."""
    from scipy.optimize import least_squares                            # heavy (scipy.optimize, ~0.3 s)

    lb, ub = bounds
    tol = dict(xtol=1e-12, ftol=1e-12, gtol=1e-12)
    bounded = bool(np.isfinite(lb).any() or np.isfinite(ub).any())
    if not robust:
        res = least_squares(fun, z0, jac=jac, method="lm", max_nfev=max_nfev, **tol)
        if not bounded or (np.all(res.x >= lb) and np.all(res.x <= ub)):
            return res
        z0 = np.clip(res.x, lb, ub)
    return least_squares(fun, z0, jac=jac, method="trf", bounds=(lb, ub) if bounded else (-np.inf, np.inf),
                         loss="soft_l1" if robust else "linear", f_scale=f_scale, max_nfev=max_nfev, **tol)


def parameter_value(p: ModelParams, info: ParamInfo, x_int: float) -> float:
    """Contract-unit value: DH rows as errors (dtheta) or absolute (d, a, alpha, beta), c, base, tool absolute."""
    i = info.index
    k = info.kind
    if k == "dtheta":
        return float(x_int / INTERNAL_SCALE["deg"])
    if k == "d":
        return float(p.d[i])
    if k == "a":
        return float(p.a[i])
    if k == "alpha":
        return float(np.rad2deg(p.alpha[i]))
    if k == "beta":
        return float(np.rad2deg(p.beta[i]))
    if k == "c":
        return float(p.c[i])
    if k in HARMONICS:
        return float(np.rad2deg(p.h[i, list(HARMONICS).index(k)]))
    if k == "base_t":
        return float(p.base[i])
    if k == "base_r":
        return float(p.base[3 + i])
    if k == "fixture":
        return float(x_int)
    return float(p.tool["xyz".index(info.name[-1])])


def data_name(positions) -> str:
    """What the user measured: a MultiCal campaign (clamping positions) or instrument points."""
    return "campaign" if len(positions) else "data set"
