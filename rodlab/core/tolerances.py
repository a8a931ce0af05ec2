"""The rod as built around its design: tolerances of a design's dotted keys (contract v1.1 ``[tolerances]``).

A tolerance is one standard deviation of a key of the ``*.rod.toml`` file, absolute in the key's unit
(``"tube.outer_diameter_mm" = 0.05``) or relative as a string (``"materials.cfrp_tube.E_GPa" = "15%"``). Keys the
file does not list get the documented defaults below (:data:`DEFAULT_RULES`), by material class and part; a value
of ``0`` in the file removes a default.

Default tolerances (one standard deviation):

=============================  ===================  =================================================================
key                            default              why
=============================  ===================  =================================================================
``materials.M.E_GPa``          laminate 15 %,       M is the material of a tube or of the bend. A laminate's axial
                               metal 3 %            modulus varies with fibre volume, lay-up angle and cure; the
                                                    paper's own carbon rods are 23-130 % softer than simulated
                                                    (Table 2 r_rod). Metals: handbook scatter.
``materials.M.G_GPa``          laminate 20 %        only where the file gives G (a laminate's shear modulus, matrix
                                                    dominated, scatters more than E)
``tube.outer_diameter_mm``     0.05 mm              drawn / rolled tube, +-0.1 mm at two standard deviations
``tube.wall_mm``               5 %                  +-10 % wall at two standard deviations
``bend.radius_mm``             5 %                  a bent pipe's radius (present only with a bend)
``rings.length_mm``            10 %                 the bonded length that carries load (adhesive fillets, seating)
=============================  ===================  =================================================================

``[pipe_I]`` / ``[pipe_II]`` tables that override the tube get the tube's defaults under their own keys.

Bonds: the joints a design models as rigid (the flange clamp, ring 1, pipe II: ring 2 and the ball holder) get a
bending compliance tolerance ``joints.PLACE.s_bend_rad_per_Nm`` [rad/(N m)], default :data:`BOND_SD` (a sound epoxy
sleeve bond is stiffer than ~3e-7 rad/(N m); 1e-6 allows a partly starved one); a compliant joint is named only
beyond it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .design import RodDesign
from .errors import DesignError, did_you_mean
from .joint_springs import JOINT_KEYS, JOINT_PLACES

__all__ = ["defaults_markdown", "bond_tolerances", "JOINT_PLACES", "BOND_SD", "ToleranceParam", "design_tolerances",
           "parse_tolerance_value", "check_tolerance_table", "design_value", "numeric_keys", "DEFAULT_RULES"]

#: (key pattern, laminate sigma, metal sigma, why) of the documented defaults; ``M`` stands for a material name
DEFAULT_RULES = (
    ("materials.M.E_GPa", "15%", "3%", "modulus of a tube or bend material"),
    ("materials.M.G_GPa", "20%", None, "shear modulus given by the file (laminates)"),
    ("tube.outer_diameter_mm", 0.05, 0.05, "tube outer diameter"),
    ("tube.wall_mm", "5%", "5%", "tube wall"),
    ("bend.radius_mm", "5%", "5%", "bend radius"),
    ("rings.length_mm", "10%", "10%", "bonded ring length"),
)


#: default standard deviation of a bond's bending compliance [rad/(N m)]
BOND_SD = 1e-6


def _bond_key(key: str) -> str | None:
    """The place of a ``joints.PLACE.s_bend_rad_per_Nm`` key, else None."""
    parts = key.split(".")
    if len(parts) == 3 and parts[0] == "joints" and parts[2] == "s_bend_rad_per_Nm":
        return parts[1]
    return None


@dataclass(frozen=True)
class ToleranceParam:
    """One uncertain key of a design.

    key : dotted key of the design file (``materials.cfrp_tube.E_GPa``); nominal : the design's value [key's
    unit]; sigma : one standard deviation [key's unit]; source : ``file`` (the design's ``[tolerances]``) or
    ``default`` (:data:`DEFAULT_RULES`)
    """

    key: str
    nominal: float
    sigma: float
    source: str = "default"

    def __post_init__(self) -> None:
        for name in ("nominal", "sigma"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise DesignError(f"tolerance of {self.key}: {name} must be a finite number, got {v!r}", key=self.key)
        if self.sigma < 0:
            raise DesignError(f"tolerance of {self.key}: must be >= 0, got {self.sigma!r}", key=self.key)

    @property
    def relative(self) -> float:
        """sigma / |nominal| [-]"""
        return self.sigma / abs(self.nominal) if self.nominal else math.inf

    def describe(self) -> str:
        return f"{self.key} = {self.nominal:g} +- {self.sigma:.3g} ({self.relative:.1%}, {self.source})"


#: a stated tolerance (one standard deviation) of at least this share of its value is refused: no part is made
#: that loosely, and the linear propagation of the envelope would not hold
TOLERANCE_MAX_SHARE = 0.5


def parse_tolerance_value(value, nominal: float, key: str) -> float:
    """One standard deviation in the key's unit from a tolerance entry: a number (absolute) or ``"N%"``."""
    if isinstance(value, str):
        text = value.strip()
        if not text.endswith("%"):
            raise DesignError(f"expected a number (absolute, in the key's unit) or a percentage such as \"5%\", got "
                              f"{value!r}", key=f"tolerances.{key}")
        try:
            pct = float(text[:-1])
        except ValueError:
            raise DesignError(f"expected a percentage such as \"5%\", got {value!r}", key=f"tolerances.{key}") from None
        if not math.isfinite(pct) or pct < 0:
            raise DesignError(f"a percentage must be finite and >= 0, got {value!r}", key=f"tolerances.{key}")
        return abs(nominal) * pct / 100.0
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value < 0:
        raise DesignError(f"expected a number >= 0 (one standard deviation in the key's unit) or \"N%\", got "
                          f"{value!r}", key=f"tolerances.{key}")
    return float(value)


def numeric_keys(design: RodDesign) -> dict[str, float]:
    """Every numeric dotted key of ``design`` as a file would spell it, with its value: the top-level lengths,
    ``tube.*`` (pipes that share the tube) or ``pipe_I.*`` / ``pipe_II.*``, the parts' keys,
    ``materials.NAME.*`` of every material used and ``joints.PLACE.*`` (0 where the design declares no joint)."""
    d = design
    out = {"L1_mm": d.L1_mm, "L2_mm": d.L2_mm, "gamma_deg": d.gamma_deg}
    for label, pipe in (("pipe_I", d.pipe_I), ("pipe_II", d.pipe_II)):
        table = "tube" if pipe.key == "tube" else label
        out.setdefault(f"{table}.outer_diameter_mm", pipe.outer_diameter_mm)
        out.setdefault(f"{table}.wall_mm", pipe.wall_mm)
        out[f"{label}.outer_diameter_mm"] = pipe.outer_diameter_mm
        out[f"{label}.wall_mm"] = pipe.wall_mm
    out.update({"bend.outer_diameter_mm": d.bend.outer_diameter_mm, "bend.wall_mm": d.bend.wall_mm,
                "bend.radius_mm": d.bend.radius_mm, "ball.diameter_mm": d.ball.diameter_mm})
    for label in ("rings", "pipe_holder", "ball_holder"):
        part = getattr(d, label)
        out[f"{label}.outer_diameter_mm"] = part.outer_diameter_mm
        out[f"{label}.length_mm"] = part.length_mm
    for m in _materials(d):
        out[f"materials.{m.name}.E_GPa"] = m.E_GPa
        out[f"materials.{m.name}.G_GPa"] = m.G_axial_GPa
        out[f"materials.{m.name}.nu"] = m.nu
        out[f"materials.{m.name}.density_kg_m3"] = m.density_kg_m3
        if m.E_transverse_GPa is not None:
            out[f"materials.{m.name}.E_transverse_GPa"] = m.E_transverse_GPa
    for place in JOINT_PLACES:                 # a bond the design does not declare is rigid: 0
        spring = d.joints.get(place)
        for k in JOINT_KEYS:
            out[f"joints.{place}.{k}"] = getattr(spring, k) if spring is not None else 0.0
    return out


def design_value(design: RodDesign, key: str) -> float:
    """The value of the dotted ``key`` in ``design``; :class:`DesignError` naming the known keys otherwise."""
    keys = numeric_keys(design)
    if key not in keys:
        raise DesignError(f"no numeric key {key!r} in design {design.name!r}." + did_you_mean(key, list(keys)),
                          key=key)
    return float(keys[key])


def check_tolerance_table(design: RodDesign, table: dict) -> dict[str, float]:
    """{key: one standard deviation} of a ``[tolerances]`` table, every key checked against the design; every
    problem of the table at once (the first raised, the others in its ``also``)."""
    out, problems = {}, []
    for key, value in table.items():
        try:
            out[key] = _tolerance_entry(design, key, value)
        except DesignError as e:
            problems.append(e)
    if problems:
        first = problems[0]
        raise DesignError(first.detail, path=first.path, line=first.line, key=first.key, also=problems[1:])
    return out


def _tolerance_entry(design: RodDesign, key: str, value) -> float:
    """One standard deviation of the tolerance ``key = value`` (a bond's absolute, else in the key's unit or a
    percentage of its design value); raises :class:`DesignError` naming ``tolerances.KEY``."""
    place = _bond_key(key)
    if place is not None:
        if place not in JOINT_PLACES:
            raise DesignError(f"unknown joint place {place!r}; places: {list(JOINT_PLACES)}." +
                              did_you_mean(place, JOINT_PLACES), key=f"tolerances.{key}")
        if isinstance(value, str):
            raise DesignError(f"a bond's tolerance is absolute [rad/(N m)] (its design value is 0), got {value!r}",
                              key=f"tolerances.{key}")
        return parse_tolerance_value(value, 0.0, key)
    nominal = design_value(design, key) if key in numeric_keys(design) else None
    if nominal is None:
        raise DesignError(f"unknown key {key!r}: a tolerance names a numeric key of the design file." +
                          did_you_mean(key, list(numeric_keys(design))), key=f"tolerances.{key}")
    sd = parse_tolerance_value(value, nominal, key)
    if nominal and sd >= TOLERANCE_MAX_SHARE * abs(nominal):
        meant = ("a tolerance is one standard deviation, not a range: a few % is usual for a made part (\"5%\")"
                 if isinstance(value, str) else f"an absolute tolerance in the wrong unit, or meant as a percentage "
                 f"(\"{value:g}%\")?")
        raise DesignError(f"one standard deviation of {sd:g} on a value of {nominal:g} (its tolerance is "
                          f"{sd / abs(nominal):.0%} of it; {TOLERANCE_MAX_SHARE:.0%} or more is refused: "
                          f"no part is made that loosely): {meant}", key=f"tolerances.{key}")
    return sd


def design_tolerances(design: RodDesign) -> list[ToleranceParam]:
    """The design's uncertain keys: its ``[tolerances]`` over the documented defaults (:data:`DEFAULT_RULES`);
    zero tolerances left out."""
    given = {k: v for k, v in check_tolerance_table(design, dict(design.tolerances)).items() if _bond_key(k) is None}
    params = {}
    for key, sigma in _defaults(design).items():
        params[key] = ToleranceParam(key, design_value(design, key), sigma, "default")
    for key, sigma in given.items():
        params[key] = ToleranceParam(key, design_value(design, key), sigma, "file")
    return [p for p in params.values() if p.sigma > 0]


def bond_tolerances(design: RodDesign) -> dict[str, float]:
    """{place: one standard deviation of the bond's bending compliance [rad/(N m)]}: the file's
    ``joints.PLACE.s_bend_rad_per_Nm`` over :data:`BOND_SD`; zero tolerances left out."""
    out = dict.fromkeys(JOINT_PLACES, BOND_SD)
    for key, sd in check_tolerance_table(design, dict(design.tolerances)).items():
        if _bond_key(key) is not None:
            out[_bond_key(key)] = sd
    return {k: v for k, v in out.items() if v > 0}


def _materials(design: RodDesign) -> list:
    """The materials of the tubes and the bend (the members whose stiffness the tolerances move), once each."""
    seen = {}
    parts = [design.pipe_I, design.pipe_II] + ([design.bend] if design.has_bend else [])
    for part in parts:
        seen.setdefault(part.material.name, part.material)
    return list(seen.values())


def _defaults(design: RodDesign) -> dict[str, float]:
    """{key: sigma} of the documented defaults for ``design``."""
    out = {}
    for m in _materials(design):
        laminate = not m.is_isotropic
        for pattern, lam, metal, _ in DEFAULT_RULES[:2]:
            rule = lam if laminate else metal
            key = pattern.replace(".M.", f".{m.name}.")
            if rule is None or (key.endswith("G_GPa") and m.G_GPa is None):
                continue
            out[key] = parse_tolerance_value(rule, design_value(design, key), key)
    keys = numeric_keys(design)
    tube_tables = sorted({"tube" if p.key == "tube" else lbl for lbl, p in (("pipe_I", design.pipe_I),
                                                                           ("pipe_II", design.pipe_II))})
    laminate_tube = not design.pipe_I.material.is_isotropic
    for pattern, lam, metal, _ in DEFAULT_RULES[2:]:
        table, name = pattern.split(".")
        tables = tube_tables if table == "tube" else [table]
        for t in tables:
            key = f"{t}.{name}"
            if key not in keys or keys[key] <= 0 or (t == "bend" and not design.has_bend):
                continue
            out[key] = parse_tolerance_value(lam if laminate_tube else metal, keys[key], key)
    return out


def defaults_markdown() -> str:
    """The documented defaults as the Markdown table of docs/formats.md (generated: ``scripts/gen_cli_docs.py``)."""
    rows = ["| key | laminate (E_transverse or G given) | metal / isotropic | what |", "|---|---|---|---|"]
    for pattern, lam, metal, why in DEFAULT_RULES:
        def cell(v):
            return "-" if v is None else (f"{v} mm" if isinstance(v, float) else v)
        rows.append(f"| `{pattern}` | {cell(lam)} | {cell(metal)} | {why} |")
    rows.append(f"| `joints.PLACE.s_bend_rad_per_Nm` ({', '.join(JOINT_PLACES)}) | {BOND_SD:g} rad/(N m) | "
                f"{BOND_SD:g} rad/(N m) | a bond modelled as rigid (absolute only) |")
    return "\n".join(rows)
