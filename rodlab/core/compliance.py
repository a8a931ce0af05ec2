"""Rod compliance (paper Eqs. 16, 18, 19, 21-23) and the ``*.compliance.json`` file format.

``C_F`` maps a force on the ball centre (N, in {T}) to the ball-centre displacement (mm, in {T});
``C_g`` maps gravity expressed in {T} in units of g0 to the displacement (mm) caused by the rod's
own weight. Eq. 19: ``dx_TCP = C_g g^T + C_F F^T``.
"""
from __future__ import annotations

import hashlib
import json
import logging
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import __version__
from .design import RodDesign
from .enums import Method
from .errors import ComplianceError, did_you_mean
from .fileio import atomic_write_json, json_safe, read_json, sha256_file
from .massprops import mass_properties
from .schema import require_schema

__all__ = ["RodCompliance", "c_rod_um", "r_rod", "r_mn", "DEFAULT_CONTACT_FORCE_N", "FORMAT_COMPLIANCE",
           "FORMAT_COMPLIANCE_V2", "COMPLIANCE_FORMATS", "read_compliance", "write_compliance", "design_hash"]

log = logging.getLogger(__name__)

FORMAT_COMPLIANCE = "rodlab.compliance/1"
#: written when a file carries ``r_mn`` or ``C_F_sigma_mm_per_N`` (else /1, so existing files keep their format)
FORMAT_COMPLIANCE_V2 = "rodlab.compliance/2"
COMPLIANCE_FORMATS = (FORMAT_COMPLIANCE, FORMAT_COMPLIANCE_V2)
#: Contact force of the three sensors on the ball, in {D} [N] (paper Section 5.2).
DEFAULT_CONTACT_FORCE_N = np.array([1.10, 1.25, 1.05])
#: Relative asymmetry of C_F accepted on read (Maxwell-Betti; measured files are noisy).
SYMMETRY_RTOL = 0.05
#: Largest plausible compliance entry [mm/N or mm per g0]
MAX_COMPLIANCE = 1e3
#: beyond these a compliance file's numbers are not a measuring rod's but a unit slip (warned of on reading): C_F
#: diagonal [mm/N] (um/N written as mm/N), mass [kg] (grams), the tool vector's length [mm] (metres)
PLAUSIBLE_C_F_MM_PER_N = 2.0
PLAUSIBLE_MASS_KG = 25.0
PLAUSIBLE_TOOL_MM = 20.0

_KEYS = ("format", "rod", "method", "C_F_mm_per_N", "C_g_mm_per_g0", "r_rod", "c_rod_um", "mass_kg",
         "com_T_mm", "tool_mm", "provenance", "r_mn", "C_F_sigma_mm_per_N")
#: keys of rodlab.compliance/2 only
_V2_KEYS = ("r_mn", "C_F_sigma_mm_per_N")
_REQUIRED = ("format", "rod", "method", "C_F_mm_per_N", "C_g_mm_per_g0", "mass_kg", "com_T_mm", "tool_mm")


def c_rod_um(C_F: np.ndarray, C_g: np.ndarray, force_N: float | None = None) -> float:
    """Compliance index (paper Eq. 23) [um]: ``sum(C_g) + sum(C_F) |F|``, signed sums of all nine entries.

    ``force_N`` is the magnitude of the contact force; default ``|[1.10, 1.25, 1.05]|`` N.
    """
    C_F, C_g = _matrix33(C_F, "C_F"), _matrix33(C_g, "C_g")
    if force_N is None:
        f = float(np.linalg.norm(DEFAULT_CONTACT_FORCE_N))
    else:
        try:
            v = np.asarray(force_N, float).reshape(-1)
        except (TypeError, ValueError):
            v = np.array([np.nan])
        f = float(np.linalg.norm(v)) if v.size == 3 else float(v[0]) if v.size == 1 else float("nan")
        if not (np.isfinite(f) and f > 0):       # a 3-vector is the contact force: its magnitude (Eq. 23's |F|)
            raise ComplianceError(f"force_N: expected the contact force's magnitude [N] > 0 (or its 3-vector), got "
                                  f"{force_N!r}", key="force_N")
    return float(1e3 * (np.sum(C_g) + np.sum(C_F) * f))


def _matrix33(M, name: str) -> np.ndarray:
    """``M`` as a 3 x 3 float array (NaN: an entry not measured), or a :class:`ComplianceError` naming ``name``."""
    try:
        A = np.asarray(M, dtype=float)
    except (TypeError, ValueError) as e:
        raise ComplianceError(f"{name}: expected a 3 x 3 matrix of numbers, got {type(M).__name__}", key=name) from e
    if A.shape != (3, 3):
        raise ComplianceError(f"{name}: expected a 3 x 3 matrix [mm/N or mm/g0], got shape {A.shape}", key=name)
    return A


def r_rod(C_F_meas: np.ndarray, C_F_sim: np.ndarray) -> float:
    """Overall correction factor (paper Eq. 21): ``(c22 + c33)_meas / (c22 + c33)_sim``; both 3 x 3 [mm/N], each
    ``c22 + c33`` > 0."""
    C_F_meas, C_F_sim = _matrix33(C_F_meas, "C_F_meas"), _matrix33(C_F_sim, "C_F_sim")
    num = float(C_F_meas[1, 1] + C_F_meas[2, 2])
    den = float(C_F_sim[1, 1] + C_F_sim[2, 2])
    if not den > 0:
        raise ComplianceError(f"simulated c22 + c33 must be > 0 to form r_rod, got {den}")
    if not num > 0:
        raise ComplianceError(f"measured c22 + c33 must be > 0 to form r_rod, got {num} (an unmeasured or zero C_F?)",
                              key="C_F_meas")
    return num / den


def r_mn(C_F_meas: np.ndarray, C_F_sim: np.ndarray) -> np.ndarray:
    """Per-entry correction factors (paper Eq. 20): ``C_F_meas[m, n] / C_F_sim[m, n]``, shape=(3, 3) [-];
    NaN where the entry was not measured (NaN in ``C_F_meas``) or the simulated entry is ~0 (an entry of
    ``|c| <= 1e-9 max|C_F_sim|`` has no ratio)."""
    meas = np.asarray(C_F_meas, dtype=float)
    sim = np.asarray(C_F_sim, dtype=float)
    tiny = 1e-9 * max(float(np.abs(sim).max()), 1e-300)
    ok = np.isfinite(meas) & (np.abs(sim) > tiny)
    return np.where(ok, meas / np.where(ok, sim, 1.0), np.nan)


def design_hash(design: RodDesign) -> str:
    """SHA-256 of the design's source file, or of its canonical summary when built in memory."""
    if design.source is not None and Path(design.source).exists():
        return sha256_file(design.source)
    return hashlib.sha256(json.dumps(design.summary(), sort_keys=True).encode()).hexdigest()


def _as33(value, key: str, path) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise ComplianceError(f"expected a 3x3 array of numbers, got {value!r}"[:200], path=path, key=key) from e
    if a.shape != (3, 3):
        raise ComplianceError(f"expected shape (3, 3), got {a.shape}", path=path, key=key)
    if not np.all(np.isfinite(a)):
        raise ComplianceError("entries must be finite (no NaN/inf)", path=path, key=key)
    if np.abs(a).max() > MAX_COMPLIANCE:
        raise ComplianceError(f"an entry of {np.abs(a).max():.3g} is not a measuring rod's (|entry| <= "
                              f"{MAX_COMPLIANCE:g}); check the units (mm/N, mm per g0)", path=path, key=key)
    return a


def _as33_nullable(value, key: str, path, lo: float, hi: float) -> np.ndarray:
    """A 3x3 array whose entries are numbers in [lo, hi] or null / NaN (not known), as floats with NaN."""
    try:
        rows = [[np.nan if v is None else v for v in row] for row in value] if isinstance(value, list) else value
        a = np.array(rows, dtype=float)
    except (TypeError, ValueError) as e:
        raise ComplianceError(f"expected a 3x3 array of numbers or null, got {value!r}"[:200], path=path,
                              key=key) from e
    if a.shape != (3, 3):
        raise ComplianceError(f"expected shape (3, 3), got {a.shape}", path=path, key=key)
    if np.isinf(a).any():
        raise ComplianceError("entries must be finite numbers or null (not known)", path=path, key=key)
    bad = np.isfinite(a) & ((a < lo) | (a > hi))
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise ComplianceError(f"entry [{i}][{j}] = {a[i, j]:.4g} is outside [{lo:g}, {hi:g}]", path=path, key=key)
    return a


def _null33(a: np.ndarray, sig) -> list:
    return [[None if not np.isfinite(v) else sig(v) for v in row] for row in a]


def _as3(value, key: str, path) -> np.ndarray:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as e:
        raise ComplianceError(f"expected 3 numbers, got {value!r}"[:200], path=path, key=key) from e
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise ComplianceError(f"expected 3 finite numbers, got {value!r}"[:200], path=path, key=key)
    if np.abs(a).max() > 1e5:
        raise ComplianceError(f"a coordinate of {np.abs(a).max():.3g} mm is not a measuring rod's (|x| <= 1e5 mm)",
                              path=path, key=key)
    return a


@dataclass(frozen=True)
class RodCompliance:
    """Compliance of one measuring rod, as stored in a ``*.compliance.json``.

    Attributes
    ----------
    rod : rod name
    method : how it was obtained (:class:`~rodlab.core.enums.Method`)
    C_F : force compliance in {T} [mm/N], shape=(3, 3), symmetric
    C_g : gravity compliance in {T} [mm per g0], shape=(3, 3)
    mass_kg : rod mass [kg]
    com_T_mm : rod centre of mass in {T} [mm], shape=(3,)
    tool_mm : nominal ball centre in {6} [mm], shape=(3,)
    r_rod : correction factor measured/simulated (Eq. 21) [-]
    provenance : free-form record of how the file was made
    r_mn : per-entry correction factors measured/simulated (Eq. 20) [-], shape=(3, 3), NaN where not measured;
        None when the file has none (only a measured file has them)
    C_F_sigma : standard uncertainty of the measured C_F entries [mm/N], shape=(3, 3), NaN where unknown;
        None when the file has none
    stored_c_rod_um : the c_rod_um the file stated [um] (None: not read from a file, or the file had none)
    """

    rod: str
    method: Method
    C_F: np.ndarray
    C_g: np.ndarray
    mass_kg: float
    com_T_mm: np.ndarray
    tool_mm: np.ndarray
    r_rod: float = 1.0
    provenance: dict = field(default_factory=dict)
    r_mn: np.ndarray | None = None
    C_F_sigma: np.ndarray | None = None
    stored_c_rod_um: float | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "method", Method.parse(self.method, "method"))
        if self.r_mn is not None:
            object.__setattr__(self, "r_mn", _as33_nullable(self.r_mn, "r_mn", None, -1e3, 1e3))
        if self.C_F_sigma is not None:
            object.__setattr__(self, "C_F_sigma", _as33_nullable(self.C_F_sigma, "C_F_sigma_mm_per_N", None, 0.0,
                                                                 MAX_COMPLIANCE))
        object.__setattr__(self, "C_F", _as33(self.C_F, "C_F_mm_per_N", None))
        object.__setattr__(self, "C_g", _as33(self.C_g, "C_g_mm_per_g0", None))
        object.__setattr__(self, "com_T_mm", _as3(self.com_T_mm, "com_T_mm", None))
        object.__setattr__(self, "tool_mm", _as3(self.tool_mm, "tool_mm", None))
        for key, top in (("mass_kg", 1e3), ("r_rod", 1e3)):
            v = getattr(self, key)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) or v <= 0 or v > top:
                raise ComplianceError(f"must be a finite number > 0 and <= {top:g}, got {v!r}", key=key)
        if self.method is Method.NONE:
            if np.any(self.C_F != 0) or np.any(self.C_g != 0):
                raise ComplianceError("method `none` means zero matrices (no compensation); "
                                      "use method calc/fea/meas for non-zero compliance", key="method")
            return
        scale = float(np.abs(self.C_F).max())
        asym = float(np.abs(self.C_F - self.C_F.T).max())
        if asym > SYMMETRY_RTOL * scale:
            raise ComplianceError(
                f"C_F must be symmetric (Maxwell-Betti): largest |C - C^T| = {asym:.3g} mm/N is "
                f"{asym / scale:.1%} of max|C| (tolerance {SYMMETRY_RTOL:.0%})", key="C_F_mm_per_N")
        eig = np.linalg.eigvalsh(0.5 * (self.C_F + self.C_F.T))
        if eig.min() < -1e-6 * max(scale, 1e-300):
            raise ComplianceError(f"C_F must be positive semi-definite (a passive structure); eigenvalues {eig}",
                                  key="C_F_mm_per_N")

    # -- physics ----------------------------------------------------------------------------
    @property
    def c_rod_um(self) -> float:
        """Compliance index, paper Eq. 23 [um], with the default contact force magnitude."""
        return c_rod_um(self.C_F, self.C_g)

    def offset_T_mm(self, g_T_g0: np.ndarray, F_T_N: np.ndarray) -> np.ndarray:
        """Ball-centre offset (Eq. 19) in {T} [mm], shape=(n, 3), from gravity [g0] and force [N] in {T}, shape=(n, 3)."""
        g = np.atleast_2d(np.asarray(g_T_g0, dtype=float))
        f = np.atleast_2d(np.asarray(F_T_N, dtype=float))
        return g @ self.C_g.T + f @ self.C_F.T

    # -- construction ------------------------------------------------------------------------
    @classmethod
    def from_design(cls, design: RodDesign, C_F, C_g, method: Method, provenance: dict | None = None,
                    r_rod: float = 1.0) -> "RodCompliance":
        """Fill mass, centre of mass and tool point from ``design``."""
        mp = mass_properties(design)
        prov = {"rodlab_version": __version__, "method": str(Method.parse(method)),
                "design": design.name, "design_sha256": design_hash(design)}
        if design.source is not None:
            prov["design_file"] = str(Path(design.source).resolve())   # found again from any working folder
        if design.joints:
            prov["declared_joints_rad_per_Nm"] = {p: vars(j) for p, j in design.joints.items()}
        prov.update(provenance or {})
        return cls(design.name, method, C_F, C_g, mp.mass_kg, mp.com_T_mm, design.tool_mm, r_rod, prov)

    @classmethod
    def none_like(cls, other: "RodCompliance") -> "RodCompliance":
        """Zero compliance (no compensation) with ``other``'s mass, COM and tool."""
        return cls(other.rod, Method.NONE, np.zeros((3, 3)), np.zeros((3, 3)), other.mass_kg, other.com_T_mm,
                   other.tool_mm, 1.0, {"derived_from": other.provenance.get("method", str(other.method))})

    def scaled(self, r: float, method: Method | str = Method.MEAS) -> "RodCompliance":
        """The same rod ``r`` times as compliant (``C_F``, ``C_g`` scaled; paper Eq. 22 with ``r = r_rod``),
        recorded as ``method`` with ``r_rod = r``. A measurement's ``r_mn`` and ``C_F_sigma`` are not carried:
        they describe the rig's entries, not the scaled matrices."""
        if not (isinstance(r, (int, float)) and math.isfinite(r) and r > 0):
            raise ComplianceError(f"the scale factor must be a finite number > 0, got {r!r}", key="r_rod")
        prov = dict(self.provenance, scaled_from=str(self.method), scale_factor=float(r))
        return RodCompliance(self.rod, method, self.C_F * r, self.C_g * r, self.mass_kg, self.com_T_mm,
                             self.tool_mm, float(r), prov)

    # -- (de)serialisation -----------------------------------------------------------------
    @property
    def format_id(self) -> str:
        """The format this compliance is written in: /2 when it carries ``r_mn`` or ``C_F_sigma``, else /1."""
        return FORMAT_COMPLIANCE_V2 if (self.r_mn is not None or self.C_F_sigma is not None) else FORMAT_COMPLIANCE

    def to_dict(self) -> dict:
        def sig(v, n=10):
            return float(f"{float(v):.{n}g}") + 0.0

        def r(a):
            return [[sig(v) for v in row] for row in a] if np.ndim(a) == 2 else [sig(v) for v in a]
        out = {"format": self.format_id, "rod": self.rod, "method": str(self.method),
               "C_F_mm_per_N": r(self.C_F), "C_g_mm_per_g0": r(self.C_g), "r_rod": sig(self.r_rod),
               "c_rod_um": round(self.c_rod_um, 4), "mass_kg": sig(self.mass_kg),
               "com_T_mm": r(self.com_T_mm), "tool_mm": r(self.tool_mm)}
        if self.r_mn is not None:
            out["r_mn"] = _null33(self.r_mn, sig)
        if self.C_F_sigma is not None:
            out["C_F_sigma_mm_per_N"] = _null33(self.C_F_sigma, sig)
        out["provenance"] = json_safe(self.provenance)
        return out

    @classmethod
    def from_dict(cls, data, path=None, warn_unit_slips: bool = True) -> "RodCompliance":
        if not isinstance(data, dict):
            raise ComplianceError(f"expected a JSON object, got {type(data).__name__}", path=path)
        for k in data:
            if k not in _KEYS:
                log.warning("%s: unknown key %r ignored.%s", path, k, did_you_mean(k, _KEYS))
        for k in _REQUIRED:
            if k not in data:
                raise ComplianceError("missing required key." + did_you_mean(k, list(data)), path=path, key=k)
        if data["format"] not in COMPLIANCE_FORMATS:
            raise ComplianceError(f"expected one of {list(COMPLIANCE_FORMATS)}, got {data['format']!r}",
                                  path=path, key="format")
        for k in _V2_KEYS:
            if k in data and data["format"] == FORMAT_COMPLIANCE:
                raise ComplianceError(f"`{k}` is a key of {FORMAT_COMPLIANCE_V2!r}; this file states "
                                      f"{FORMAT_COMPLIANCE!r}. Fix: set \"format\": \"{FORMAT_COMPLIANCE_V2}\"",
                                      path=path, key=k)
        if not isinstance(data["rod"], str):
            raise ComplianceError(f"expected a string, got {data['rod']!r}", path=path, key="rod")
        if not isinstance(data.get("provenance", {}), dict):
            raise ComplianceError("expected an object", path=path, key="provenance")
        try:
            method = Method.parse(data["method"])
        except ValueError as e:
            raise ComplianceError(str(e), path=path, key="method") from e
        for k in ("mass_kg", "r_rod", "c_rod_um"):
            v = data.get(k, 1.0)
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise ComplianceError(f"expected a number, got {v!r}", path=path, key=k)
        try:
            comp = cls(data["rod"], method, _as33(data["C_F_mm_per_N"], "C_F_mm_per_N", path),
                       _as33(data["C_g_mm_per_g0"], "C_g_mm_per_g0", path), float(data["mass_kg"]),
                       _as3(data["com_T_mm"], "com_T_mm", path), _as3(data["tool_mm"], "tool_mm", path),
                       float(data.get("r_rod", 1.0)), dict(data.get("provenance", {})),
                       _optional33(data, "r_mn", path, -1e3, 1e3),
                       _optional33(data, "C_F_sigma_mm_per_N", path, 0.0, MAX_COMPLIANCE),
                       None if data.get("c_rod_um") is None else float(data["c_rod_um"]))
        except ComplianceError as e:
            if e.path is None:
                raise ComplianceError(str(e).split(": ", 1)[-1] if e.key else str(e), path=path, key=e.key) from e
            raise
        if comp.stored_c_rod_um is not None and not comp.c_rod_as_stated:
            log.warning("%s: stored c_rod_um %.4g differs from Eq. 23 on the matrices (%.4g); the matrices are used",
                        path, comp.stored_c_rod_um, comp.c_rod_um)
        for problem in (comp.unit_slips() if path is not None and warn_unit_slips else ()):  # a user's file
            log.warning("%s: %s", path, problem)
        return comp

    @property
    def simulated_by_rodlab(self) -> bool:
        """Whether rodlab simulated this file from a design (its provenance names the rodlab version and the
        design, and it states the c_rod_um its matrices give): its numbers are the design's, however soft, not a
        unit slip (a designer trial: a 3 m rod's own FEA file had been told to divide C_F by 1000; a review: a
        rodlab file's C_F scaled by hand, its provenance kept, had then slipped past)."""
        p = self.provenance or {}
        made = bool(p.get("rodlab_version")) and bool(p.get("design")) and str(self.method) in ("calc", "fea")
        return made and self.stored_c_rod_um is not None and self.c_rod_as_stated

    @property
    def c_rod_as_stated(self) -> bool:
        """Whether the file's stated c_rod_um is Eq. 23 on its matrices (to 1 %); False where it stated none."""
        stated = self.stored_c_rod_um
        return stated is not None and abs(stated - self.c_rod_um) <= 0.01 * max(abs(self.c_rod_um), 1.0)

    def unit_slips(self) -> list[str]:
        """Numbers no measuring rod has, each with the unit slip that gives them: C_F beyond
        :data:`PLAUSIBLE_C_F_MM_PER_N` (um/N written as mm/N), a mass beyond :data:`PLAUSIBLE_MASS_KG` (grams),
        a tool vector shorter than :data:`PLAUSIBLE_TOOL_MM` (metres), a centre of mass that close to the ball of a
        rod that long (metres)."""
        out = []
        worst = float(np.abs(np.diag(self.C_F)).max())
        if worst > PLAUSIBLE_C_F_MM_PER_N and not self.simulated_by_rodlab:
            out.append(f"C_F_mm_per_N reaches {worst:.4g} mm/N on its diagonal; a measuring rod deflects 0.001-0.3 mm "
                       "per N at its ball: if the file is in um/N, divide C_F by 1000")
        if self.mass_kg > PLAUSIBLE_MASS_KG:
            out.append(f"mass_kg {self.mass_kg:g}: a measuring rod weighs 0.2-5 kg; if this is grams, divide by 1000")
        if 0 < float(np.linalg.norm(self.tool_mm)) < PLAUSIBLE_TOOL_MM:
            out.append(f"tool_mm {np.round(self.tool_mm, 4).tolist()} is {np.linalg.norm(self.tool_mm):.3g} mm long; a "
                       "measuring rod's ball sits 100-1500 mm from the flange: if this is metres, multiply by 1000")
        com, reach = float(np.linalg.norm(self.com_T_mm)), float(np.linalg.norm(self.tool_mm))
        if self.mass_kg > 0 and reach >= PLAUSIBLE_TOOL_MM and 0 < com < 0.02 * reach and 1000.0 * com <= 2.0 * reach:
            out.append(f"com_T_mm {np.round(self.com_T_mm, 4).tolist()} puts the rod's centre of mass {com:.3g} mm from "
                       f"its ball, whose flange is {np.linalg.norm(self.tool_mm):.0f} mm away (a rod's centre of mass "
                       "lies along it, tens to hundreds of mm from the ball): if this is metres, multiply by 1000")
        return out


def _optional33(data: dict, key: str, path, lo: float, hi: float) -> np.ndarray | None:
    return None if data.get(key) is None else _as33_nullable(data[key], key, path, lo, hi)


def read_compliance(path: str | Path, warn_unit_slips: bool = True) -> RodCompliance:
    """Read and check a ``*.compliance.json`` (errors name the file, line and key); numbers no rod has (a unit slip:
    :meth:`RodCompliance.unit_slips`) are logged unless ``warn_unit_slips`` is False (a caller that refuses them)."""
    p = Path(path)
    data, text = read_json(p, ComplianceError)
    if isinstance(data, dict) and data.get("format") in COMPLIANCE_FORMATS:
        require_schema(data, data["format"], p, text, ComplianceError)
    return RodCompliance.from_dict(data, p, warn_unit_slips)


def write_compliance(comp: RodCompliance, path: str | Path) -> Path:
    """Write a compliance file atomically."""
    return atomic_write_json(path, comp.to_dict())
