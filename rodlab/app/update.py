"""Model updating: fit a design's uncertain keys to a measured compliance (``rodlab update``).

The structural-dynamics practice: the freed dotted keys of the design (``materials.cfrp_tube.E_GPa``,
``tube.wall_mm``, ...) are fitted, bounded and with priors from the design's tolerances where it states them, so
that the compliance model (the calibrated frame by default) reproduces the measured C_F entries within their
uncertainty plus the model's own accuracy (:data:`rodlab.core.sensitivity.METHOD_ACCURACY`). The result says what
each key became with its uncertainty, their correlations, which keys the measurement cannot separate and which
extra measurement would, and the r_mn (measured / model, entry by entry) before and after.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares
from scipy.special import chdtrc

from rodlab.fea.frame import frame_compliance
from ..core.calc import calc_rod_compliance
from ..core.design import RodDesign
from ..core.design_io import design_to_dict
from ..core.errors import LocatedError, DesignError, RodlabError
from ..core.massprops import mass_properties
from ..core.sensitivity import (METHOD_ACCURACY, method_accuracy, MODULI, MODULUS_KEYS, STRUCTURAL_ENTRIES, scale_moduli,
                                with_values)
from ..core.tolerances import BOND_SD, bond_tolerances, design_tolerances, design_value

__all__ = ["Measured", "UpdateResult", "update_design", "model_compliance", "SEPARATE_CORR", "EXPLAIN_P", "ROUGH_P",
           "MODULI", "design_with", "as_built_values", "key_value"]

#: below this tail probability of the chi-square after the fit, the freed keys do not explain the measurement
EXPLAIN_P = 1e-3
#: below this one they explain it roughly: the uncertainties are widened by the Birge ratio sqrt(chi2 / dof)
ROUGH_P = 0.05
#: two freed keys whose estimates correlate beyond this are reported as not separable
SEPARATE_CORR = 0.95
#: prior of a freed key the design gives no tolerance for: this relative standard deviation (weak)
WEAK_PRIOR = 0.5
#: a freed joint's compliance: prior standard deviation and reach, this many times a sound bond's tolerance (1e-2
#: rad/(N m) for the default 1e-6): a joint is freed because the rod shows it, so its size is the data's, not a
#: prior's (a technician trial: a prior of 100 tolerances had held a 2e-3 joint at 1.7e-3, and the update refused)
JOINT_REACH = 1e4
#: extra measurements that may separate keys: (what, standard uncertainty)
_MASS_SD_KG = 0.001
_ENTRY_REL = 0.005
_CALIPER_MM = 0.01
_COUPON_REL = 0.02


@dataclass(frozen=True)
class Measured:
    """A measured linear compliance: entries (m, n); C [mm/N], shape=(k,); cov [(mm/N)^2], shape=(k, k); source."""

    entries: tuple
    C: np.ndarray
    cov: np.ndarray
    source: str

    def __post_init__(self) -> None:
        k = len(self.entries)
        if k == 0 or np.shape(self.C) != (k,) or np.shape(self.cov) != (k, k):
            raise RodlabError(f"a measured compliance needs at least one entry with its covariance; got {k} entries, "
                              f"C {np.shape(self.C)}, cov {np.shape(self.cov)}")


@dataclass
class UpdateResult:
    """The fitted keys (scipy-``OptimizeResult`` style).

    keys; nominal, x, sigma : design values, fitted values, standard uncertainties [key units], shape=(k,);
    corr : correlations, shape=(k, k); inseparable : [(key, the keys it cannot be told from, multiple correlation of
    their data columns, what would separate them)];
    r_before, r_after : measured / model per entry; entries; chi2_before, chi2_after : of the entries;
    design : the design as built; success, message; p_after : the chi-square's tail probability after the fit
    (degrees of freedom: entries - keys, at least 1)
    """

    keys: tuple
    nominal: np.ndarray
    x: np.ndarray
    sigma: np.ndarray
    corr: np.ndarray
    inseparable: list
    entries: tuple
    r_before: np.ndarray
    r_after: np.ndarray
    chi2_before: float
    chi2_after: float
    design: RodDesign
    success: bool
    message: str
    p_after: float = 1.0        #: chance of a chi-square this large after the fit if the freed keys explain it
    prior_sd: np.ndarray | None = None   #: each key's prior standard deviation [key units] (its tolerance), shape=(k,)
    sigma_scale: float = 1.0    #: the Birge ratio ``sigma`` is widened by when ``p_after`` < :data:`ROUGH_P` [-]

    def beyond_tolerance(self, factor: float = 3.0) -> list[tuple[str, float, float]]:
        """(key, relative change, relative prior SD) of the keys other than joints that moved more than ``factor``
        prior SDs: the part is not what the design says (a wrong material, the wrong file), not a tolerance."""
        if self.prior_sd is None:
            return []
        return [(k, float(x / v0 - 1), float(sd / v0)) for k, v0, x, sd in zip(self.keys, self.nominal, self.x,
                                                                               self.prior_sd)
                if not _is_joint(k) and v0 and abs(x - v0) > factor * sd]

    @property
    def explains(self) -> bool:
        """Whether the freed keys explain the measured entries (``p_after`` above :data:`EXPLAIN_P`)."""
        return self.p_after > EXPLAIN_P


#: an off-diagonal entry below this share of sqrt(c_mm c_nn) in the frame is moved additively, not in proportion
SMALL_ENTRY = 0.05


def model_compliance(model: str, sim=None, design: RodDesign | None = None):
    """design -> C_F [mm/N] of the compliance model ``frame`` (calibrated beam frame) or ``calc`` (closed form);
    with ``sim`` (the user's own simulated compliance of ``design``, :class:`~rodlab.core.compliance.RodCompliance`)
    that file moved entry by entry as the frame moves with the keys: ``C_sim * frame(d) / frame(design)`` (a trial:
    update had fitted through rodlab's frame only, refusing what the user's own simulation called consistent);
    an entry the frame makes small (below :data:`SMALL_ENTRY` of its diagonal's geometric mean: a near-zero
    coupling) moves by the frame's change instead, ``C_sim + frame(d) - frame(design)``, where a ratio of two small
    numbers would move it by any factor."""
    if sim is not None:
        base = frame_compliance(design)[0]
        C_sim = np.asarray(sim.C_F, float)
        d = np.sqrt(np.abs(np.diag(base)))
        scaled = np.abs(base) > SMALL_ENTRY * np.outer(d, d)     # entries the frame resolves: moved in proportion

        def moved(design_d):
            C = frame_compliance(design_d)[0]
            ratio = C / np.where(scaled, base, 1.0)
            return np.where(scaled, C_sim * ratio, C_sim + (C - base))
        return moved
    if model == "frame":
        return lambda d: frame_compliance(d)[0]
    if model == "calc":
        return lambda d: calc_rod_compliance(d).C_F
    raise LocatedError(f"unknown model {model!r}; expected frame or calc", key="model")


def _is_joint(key: str) -> bool:
    return key.startswith("joints.")


def key_value(design: RodDesign, key: str) -> float:
    """The design value of a freed key: 1 for :data:`MODULI`, else the dotted key's value."""
    return 1.0 if key == MODULI else design_value(design, key)


def design_with(design: RodDesign, keys, x) -> RodDesign:
    """``design`` with the freed ``keys`` at ``x``: :data:`MODULI` scales every modulus and joint first, a key freed
    beside it (a material's G for a torsion on top of a uniform scale) then takes its own fitted value."""
    values = dict(zip(keys, (float(v) for v in x)))
    factor = values.pop(MODULI, None)
    base = design if factor is None else scale_moduli(design, factor)
    return with_values(base, values) if values else base


def as_built_values(design: RodDesign, keys, x) -> dict:
    """The dotted keys a file of the rod as built sets: :data:`MODULI` spelt out as every material's moduli and
    every declared joint's compliance (a key fitted on its own keeps its fitted value)."""
    values = dict(zip(keys, (float(v) for v in x)))
    factor = values.pop(MODULI, None)
    if factor is None:
        return values
    scaled = {}
    data = design_to_dict(design)
    for name, table in data["materials"].items():
        scaled.update({f"materials.{name}.{k}": float(table[k]) * factor for k in MODULUS_KEYS
                       if table.get(k) is not None})
    for place, spring in (data.get("joints") or {}).items():
        scaled.update({f"joints.{place}.{k}": float(v) / factor for k, v in spring.items()
                       if k.startswith("s_") and v})
    return {**scaled, **values}


def _check_keys(design: RodDesign, keys: tuple) -> None:
    """Refuse keys that cannot be fitted: no key, a key without a positive value."""
    if not keys:
        raise LocatedError("no key to fit: give --free KEY[,KEY...]", key="free")
    for k in keys:
        if not _is_joint(k) and not key_value(design, k) > 0:
            raise LocatedError(f"--free {k}: its design value is {key_value(design, k):g}; only a key with a "
                              "positive value (a size, a modulus) can be fitted", key="free")


def _priors(design: RodDesign, keys) -> tuple[np.ndarray, np.ndarray]:
    """(nominal, prior sd) of each key: the design's tolerance where it has one, a bond's tolerance
    (:func:`rodlab.core.tolerances.bond_tolerances`, :data:`~rodlab.core.tolerances.BOND_SD` for torsion) for a joint's
    compliance, else a weak prior."""
    tol = {p.key: p.sigma for p in design_tolerances(design)}
    bonds = bond_tolerances(design)
    nominal = np.array([key_value(design, k) for k in keys])
    sd = []
    for k, v in zip(keys, nominal):
        if _is_joint(k):     # freed because the rod shows it: JOINT_REACH x the tolerance of a sound bond
            sound = bonds.get(k.split(".")[1], BOND_SD) if k.endswith("s_bend_rad_per_Nm") else BOND_SD
            sd.append(max(JOINT_REACH * sound, WEAK_PRIOR * v))
        else:
            sd.append(tol.get(k, WEAK_PRIOR * abs(v)) or WEAK_PRIOR * abs(v))
    return nominal, np.array(sd)


def _bounds_and_start(keys, nominal, prior_sd) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower, upper, start): 0.2-5x the design value; a joint's compliance from 0 (rigid) to the larger of 5x its
    declared value and its prior standard deviation (:data:`JOINT_REACH` sound bonds), started strictly inside."""
    lo, hi = 0.2 * np.abs(nominal), 5.0 * np.abs(nominal)
    start = np.array(nominal, float)
    for i, k in enumerate(keys):
        if _is_joint(k):
            lo[i], hi[i] = 0.0, max(5.0 * nominal[i], prior_sd[i])
            start[i] = min(max(nominal[i], 0.01 * prior_sd[i]), 0.9 * hi[i])
    return lo, hi, start


def update_design(design: RodDesign, measured: Measured, keys, model: str = "frame", sim=None) -> UpdateResult:
    """Fit ``keys`` of ``design`` to ``measured`` (bounded to 0.2-5x the design value, priors from the tolerances);
    :data:`MODULI` among them fits one factor of every modulus of the rod. ``sim``: the user's simulated compliance
    of the design, moved by the frame's sensitivities (:func:`model_compliance`), with its method's accuracy."""
    keys = tuple(keys)
    _check_keys(design, keys)
    fn = model_compliance(model, sim, design)
    E = measured.entries
    acc = METHOD_ACCURACY[model] if sim is None else method_accuracy(str(sim.method), sim.provenance.get("model"))
    nominal, prior_sd = _priors(design, keys)

    def entries_of(x):
        """The rod's entries the model predicts for keys ``x``, its bias against the solid FEA removed."""
        return acc.expected(fn(design_with(design, keys, x)), E)

    C0 = entries_of(nominal)
    S = measured.cov + acc.covariance(fn(design), E)
    W = np.linalg.inv(np.linalg.cholesky(S))

    def residual(x):
        return np.concatenate([W @ (entries_of(x) - measured.C), (x - nominal) / prior_sd])

    lo, hi, start = _bounds_and_start(keys, nominal, prior_sd)
    try:
        res = least_squares(residual, start, bounds=(lo, hi), x_scale=prior_sd, diff_step=1e-3)
    except DesignError as e:
        raise LocatedError(f"the fit of {', '.join(keys)} reached a design the rules refuse ({e.detail}); free fewer "
                          "keys or keys the measurement constrains", key="free") from e
    J = res.jac
    cov = _covariance(J)
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    corr = cov / np.outer(np.where(sd > 0, sd, 1), np.where(sd > 0, sd, 1))
    C1 = entries_of(res.x)
    z0, z1 = W @ (C0 - measured.C), W @ (C1 - measured.C)
    as_built = design_with(design, keys, res.x)
    insep = _inseparable(design, keys, res.x, J[:len(E)], fn, E)
    dof = max(len(E) - len(keys), 1)
    p_after = float(chdtrc(dof, float(z1 @ z1)))
    scale = max(1.0, float(np.sqrt(z1 @ z1 / dof))) if p_after < ROUGH_P else 1.0
    return UpdateResult(keys, nominal, res.x, sd * scale, corr, insep, E, measured.C / C0, measured.C / C1,
                        float(z0 @ z0), float(z1 @ z1), as_built, bool(res.success), str(res.message), p_after,
                        prior_sd, scale)


def _covariance(J: np.ndarray) -> np.ndarray:
    """``(J^T J)^-1`` with the columns scaled first (:func:`rodlab.calibrate.covariance.parameter_covariance`): a
    joint's compliance (1e-6 rad/(N m)) beside a modulus (GPa) spans 1e7 in column size, and the unscaled inverse
    had dropped the moduli's weak directions as numerically zero (a CalculiX trial: E 168.1 +- 0.1 GPa, correlation
    1.00 with G, 110 SDs from the truth). The priors' rows make every direction seen."""
    from rodlab.calibrate.covariance import parameter_covariance  # heavy: rodlab.calibrate loads scipy (~0.1 s)
    return parameter_covariance(J)


def _collinearity(A: np.ndarray, a: int) -> tuple[float, list]:
    """How well column ``a`` of ``A`` is reproduced by the other columns: (multiple correlation R, the indices of
    the columns that carry it)."""
    others = [i for i in range(A.shape[1]) if i != a]
    col = A[:, a]
    if not others or not np.linalg.norm(col) > 0:
        return 0.0, []
    B = A[:, others]
    coef, *_ = np.linalg.lstsq(B, col, rcond=None)
    proj = B @ coef
    share = np.abs(coef) * np.linalg.norm(B, axis=0)
    partners = [others[i] for i in np.nonzero(share > 0.1 * share.max())[0]] if share.max() > 0 else []
    return float(np.linalg.norm(proj) / np.linalg.norm(col)), partners


def _inseparable(design, keys, x, Jd, fn, E) -> list:
    """Keys the measurement cannot tell from the others: the key's column of the whitened data Jacobian is
    reproduced by the other keys' columns (multiple correlation > :data:`SEPARATE_CORR`: together they move the
    measured entries in the same proportions, so only the priors split them), each with the first extra
    measurement (a C_F entry not measured, the rod's mass, or the key itself) that brings it to 0.9 or below."""
    out = []
    for a in range(len(keys)):
        R, partners = _collinearity(Jd, a)
        if R > SEPARATE_CORR:
            out.append((keys[a], ", ".join(keys[i] for i in partners), R, _separator(design, keys, x, Jd, a, fn, E)))
    return out


def _separator(design, keys, x, Jd, a, fn, E) -> str:
    """The first candidate measurement whose information row makes key ``a`` separable."""
    for label, row in _candidate_rows(design, keys, x, fn, E):
        if _collinearity(np.vstack([Jd, row]), a)[0] <= 0.9:
            return label
    return "no single extra measurement here separates them: hold one at its design value"


def _candidate_rows(design, keys, x, fn, E):
    """(label, information row) of measurements that could be added: unmeasured entries, the mass, each key."""
    def derivs(f):
        base = f(x)
        rows = []
        for i in range(len(keys)):
            h = 1e-3 * abs(x[i]) or 1e-6
            xp = np.array(x, float)
            xp[i] += h
            rows.append((f(xp) - base) / h)
        return np.array(rows)
    names = {0: "x", 1: "y", 2: "z"}
    for m, n in STRUCTURAL_ENTRIES:
        if (m, n) in E:
            continue
        d = derivs(lambda v: fn(design_with(design, keys, v))[m, n])
        c = fn(design_with(design, keys, x))[m, n]
        if abs(c) > 0:
            yield (f"load along {names[n]}_T and read the {names[m]} gauge (c{m + 1}{n + 1})", d / (_ENTRY_REL * abs(c)))
    d = derivs(lambda v: mass_properties(design_with(design, keys, v)).mass_kg)
    yield f"weigh the rod (to {_MASS_SD_KG * 1e3:g} g)", d / _MASS_SD_KG
    for i, k in enumerate(keys):
        row = np.zeros(len(keys))
        if _is_joint(k):
            row[i], how = 1.0 / (0.2 * BOND_SD), "two dial gauges across the bond under a side load, its rotation"
        elif k.endswith("_mm"):
            row[i], how = 1.0 / _CALIPER_MM, f"a caliper or micrometer, {_CALIPER_MM:g} mm"
        else:
            row[i], how = 1.0 / (_COUPON_REL * abs(x[i]) or 1.0), f"a coupon test, {_COUPON_REL:.0%}"
        yield f"measure {k} directly ({how})", row
