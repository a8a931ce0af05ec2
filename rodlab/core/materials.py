"""Material library: elastic constants and density of the parts of a measuring rod.

Isotropic materials carry ``E`` and ``nu`` (``G = E / (2 (1 + nu))``). Carbon-fibre tubes are
*transversely isotropic about the local tube axis*: ``E`` is the axial modulus (bending,
tension), ``E_transverse`` the modulus across the tube, and ``G`` the axial (in-plane)
shear modulus that sets the torsion of a tube. For carbon ``G`` is low (a few GPa for a
pultruded or unidirectional tube), so an isotropic model with ``G = E/2.6`` over-predicts
torsional stiffness many times over: keep ``G`` explicit.

Built-in values and their sources (room temperature, typical, not guaranteed):

- ``cfrp``: pultruded / unidirectional carbon-epoxy tube, fibre volume ~60 %. E_axial 125 GPa,
  E_transverse 9 GPa, G_12 4.5 GPa, nu_12 0.30, 1560 kg/m^3. Typical of T700-class unidirectional
  laminates (Toray T700S data sheet, 0 deg composite modulus 135 GPa at 60 % Vf; transverse and
  shear values from Daniel & Ishai, *Engineering Mechanics of Composite Materials*, 2nd ed.,
  Table A.4, carbon/epoxy AS4/3501-6: E2 = 8.96 GPa, G12 = 7.1 GPa) lowered for pultrusion.
- ``cfrp_rolled``: roll-wrapped carbon tube with +-45 deg plies (quasi-isotropic wall):
  E 70 GPa, E_transverse 20 GPa, G 15 GPa, nu 0.30, 1550 kg/m^3 (tube manufacturers' data for
  0/+-45 layups; stiffer in torsion, softer in bending than ``cfrp``).
- ``steel_304``: AISI 304 stainless, E 193 GPa, nu 0.29, 8000 kg/m^3 (ASM Handbook Vol. 1;
  AK Steel 304/304L product data bulletin).
- ``al_7075``: 7075-T6, E 71.7 GPa, nu 0.33, 2810 kg/m^3 (ASM Aerospace Specification Metals,
  MatWeb 7075-T6).
- ``al_6061``: 6061-T6, E 68.9 GPa, nu 0.33, 2700 kg/m^3 (ASM / MatWeb 6061-T6).
- ``ti_6al4v``: Ti-6Al-4V grade 5, E 113.8 GPa, nu 0.342, 4430 kg/m^3 (ASM / MatWeb).
- ``alumina``: 99.8 % Al2O3 (ball grade), E 370 GPa, nu 0.22, 3950 kg/m^3 (CoorsTek AD-998, CeramTec).
- ``zirconia``: 3Y-TZP, E 205 GPa, nu 0.31, 6050 kg/m^3 (CoorsTek YTZP data sheet).
- ``si3n4``: hot-pressed silicon nitride, E 310 GPa, nu 0.27, 3200 kg/m^3 (Kyocera SN-240 data).
- ``epoxy``: structural epoxy adhesive, E 3.0 GPa, nu 0.35, 1200 kg/m^3 (3M Scotch-Weld
  DP490 / Loctite EA 9466 technical data, cured).

A design file may define its own materials (``[materials.NAME]``) with ``E_GPa``, ``nu``,
``density_kg_m3`` and optionally ``E_transverse_GPa``, ``G_GPa``, ``cte_ppm_K``, ``strength_MPa`` and
``shear_strength_MPa`` (thermal growth and strength margins of ``rodlab study``).

Thermal expansion (axial, 1e-6/K) and allowables (MPa), typical room-temperature values: UD carbon -0.4 /
1200 (compression governs), rolled carbon 2.0 / 600, 304 stainless 17.3 / 215 (0.2 % yield), 7075-T6 23.4 /
503, 6061-T6 23.6 / 276, Ti-6Al-4V 8.6 / 880, alumina 8.2 / 379 (flexural), zirconia 10.3 / 900, Si3N4 3.3 /
800, epoxy 55 / 40 tensile and 25 MPa lap shear (DP490 on etched aluminium) — same sources as above.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from collections.abc import Mapping

from .errors import DesignError, did_you_mean

__all__ = ["Material", "BUILTIN_MATERIALS", "get_material", "material_from_table"]

_ISO_TOL = 1e-6


#: moduli [GPa] and densities [kg/m^3] of the solid materials a rod's parts are made of (polymers to carbides,
#: plastics to tungsten); a modulus outside, a density above, is refused as a units slip
MODULUS_GPA = (0.1, 1500.0)
DENSITY_KG_M3 = (100.0, 25000.0)
#: densities [kg/m^3] that are a solid's in g/cm^3 (refused with the conversion); below, a deliberately massless
#: part of an idealised model; between this and the range above, a foam
G_CM3 = (0.1, 30.0)


@dataclass(frozen=True)
class Material:
    """Linear-elastic material.

    Attributes
    ----------
    name : identifier used in designs
    E_GPa : Young's modulus [GPa]; the axial (fibre-direction) modulus if transversely isotropic
    nu : Poisson's ratio [-] (major ratio nu_12 for a transversely isotropic material)
    density_kg_m3 : density [kg/m^3]
    E_transverse_GPa : modulus across the tube axis [GPa]; ``None`` = ``E_GPa``
    G_GPa : axial shear modulus [GPa]; ``None`` = ``E / (2 (1 + nu))``
    cte_ppm_K : axial coefficient of thermal expansion [1e-6 / K] (along the tube); ``None`` = unknown
    strength_MPa : allowable normal stress [MPa] (yield for metals, the lower of the axial tensile and
        compressive strength for composites, the tensile / lap-shear strength for adhesives); ``None`` = unknown
    shear_strength_MPa : allowable shear stress [MPa] (adhesives: lap-shear strength); ``None`` = unknown
    source : where the numbers come from (free text)
    """

    name: str
    E_GPa: float
    nu: float
    density_kg_m3: float
    E_transverse_GPa: float | None = None
    G_GPa: float | None = None
    cte_ppm_K: float | None = None
    strength_MPa: float | None = None
    shear_strength_MPa: float | None = None
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        for key in ("E_GPa", "nu", "density_kg_m3", "E_transverse_GPa", "G_GPa", "cte_ppm_K", "strength_MPa",
                    "shear_strength_MPa"):
            v = getattr(self, key)
            if v is None:
                continue
            if not isinstance(v, (int, float)) or isinstance(v, bool) or not math.isfinite(v):
                raise DesignError(f"material `{self.name}`: {key} must be a finite number, got {v!r}",
                                  key=key)
        if self.E_GPa <= 0:
            raise DesignError(f"material `{self.name}`: E_GPa must be > 0, got {self.E_GPa}", key="E_GPa")
        if not (-1.0 < self.nu < 0.5):
            raise DesignError(f"material `{self.name}`: nu must lie in (-1, 0.5), got {self.nu}", key="nu")
        if self.density_kg_m3 <= 0:
            raise DesignError(f"material `{self.name}`: density_kg_m3 must be > 0, got {self.density_kg_m3}",
                              key="density_kg_m3")
        for key in ("E_transverse_GPa", "G_GPa", "strength_MPa", "shear_strength_MPa"):
            v = getattr(self, key)
            if v is not None and v <= 0:
                raise DesignError(f"material `{self.name}`: {key} must be > 0, got {v}", key=key)
        self._check_units()

    def _check_units(self) -> None:
        """Values no solid material has, which a units slip gives (Pa or MPa for GPa, g/cm^3 for kg/m^3)."""
        for key in ("E_GPa", "E_transverse_GPa", "G_GPa"):
            v = getattr(self, key)
            if v is not None and v > 0 and not (MODULUS_GPA[0] <= v <= MODULUS_GPA[1]):
                hint = (f"{v:g} Pa = {v * 1e-9:g} GPa" if v > 1e6 else f"{v:g} MPa = {v * 1e-3:g} GPa"
                        if v > MODULUS_GPA[1] else "a modulus this low is a rubber or a foam, not a rod's part")
                raise DesignError(f"material `{self.name}`: {key} = {v:g} is not a solid material's modulus in GPa "
                                  f"({MODULUS_GPA[0]:g}-{MODULUS_GPA[1]:g}; {hint}); give it in GPa", key=key)
        d = self.density_kg_m3
        if G_CM3[0] <= d <= G_CM3[1] or d > DENSITY_KG_M3[1]:
            hint = f"{d:g} g/cm^3 = {d * 1e3:g} kg/m^3" if d <= G_CM3[1] else "heavier than any metal"
            raise DesignError(f"material `{self.name}`: density_kg_m3 = {d:g} is not a solid material's density in "
                              f"kg/m^3 ({DENSITY_KG_M3[0]:g}-{DENSITY_KG_M3[1]:g}; {hint}); give it in kg/m^3",
                              key="density_kg_m3")

    @property
    def E_t_GPa(self) -> float:
        """Transverse modulus [GPa] (``E_GPa`` if isotropic)."""
        return self.E_GPa if self.E_transverse_GPa is None else float(self.E_transverse_GPa)

    @property
    def G_axial_GPa(self) -> float:
        """Axial shear modulus [GPa] (torsion of a tube)."""
        if self.G_GPa is None:
            return self.E_GPa / (2.0 * (1.0 + self.nu))
        return float(self.G_GPa)

    @property
    def is_isotropic(self) -> bool:
        """True unless a transverse modulus or an independent shear modulus was given."""
        iso_g = self.E_GPa / (2.0 * (1.0 + self.nu))
        if self.E_transverse_GPa is not None and abs(self.E_transverse_GPa - self.E_GPa) > _ISO_TOL * self.E_GPa:
            return False
        if self.G_GPa is not None and abs(self.G_GPa - iso_g) > 1e-3 * iso_g:
            return False
        return True


BUILTIN_MATERIALS: dict[str, Material] = {m.name: m for m in [
    Material("cfrp", 125.0, 0.30, 1560.0, E_transverse_GPa=9.0, G_GPa=4.5, cte_ppm_K=-0.4, strength_MPa=1200.0,
             source="pultruded/UD carbon-epoxy; Toray T700S data; Daniel & Ishai Table A.4"),
    Material("cfrp_rolled", 70.0, 0.30, 1550.0, E_transverse_GPa=20.0, G_GPa=15.0, cte_ppm_K=2.0,
             strength_MPa=600.0, source="roll-wrapped 0/+-45 carbon tube, manufacturers' data"),
    Material("steel_304", 193.0, 0.29, 8000.0, cte_ppm_K=17.3, strength_MPa=215.0,
             source="ASM Handbook Vol. 1; AK Steel 304 bulletin"),
    Material("al_7075", 71.7, 0.33, 2810.0, cte_ppm_K=23.4, strength_MPa=503.0, source="7075-T6, ASM / MatWeb"),
    Material("al_6061", 68.9, 0.33, 2700.0, cte_ppm_K=23.6, strength_MPa=276.0, source="6061-T6, ASM / MatWeb"),
    Material("ti_6al4v", 113.8, 0.342, 4430.0, cte_ppm_K=8.6, strength_MPa=880.0,
             source="Ti-6Al-4V grade 5, ASM / MatWeb"),
    Material("alumina", 370.0, 0.22, 3950.0, cte_ppm_K=8.2, strength_MPa=379.0,
             source="99.8% Al2O3 ball grade, CoorsTek AD-998 / CeramTec data"),
    Material("zirconia", 205.0, 0.31, 6050.0, cte_ppm_K=10.3, strength_MPa=900.0, source="3Y-TZP, CoorsTek YTZP"),
    Material("si3n4", 310.0, 0.27, 3200.0, cte_ppm_K=3.3, strength_MPa=800.0, source="hot-pressed Si3N4, Kyocera SN-240"),
    Material("epoxy", 3.0, 0.35, 1200.0, cte_ppm_K=55.0, strength_MPa=40.0, shear_strength_MPa=25.0,
             source="structural epoxy adhesive, DP490 / EA 9466 TDS"),
]}

_MATERIAL_KEYS = ("E_GPa", "nu", "density_kg_m3", "E_transverse_GPa", "G_GPa", "cte_ppm_K", "strength_MPa",
                  "shear_strength_MPa", "source")
_NUMBER_KEYS = _MATERIAL_KEYS[:-1]
_REQUIRED_KEYS = ("E_GPa", "nu", "density_kg_m3")


def material_from_table(name: str, table: Mapping, path=None) -> Material:
    """Build a user material from a ``[materials.NAME]`` TOML table (errors name the key)."""
    if not isinstance(table, Mapping):
        raise DesignError(f"[materials.{name}] must be a table", path=path, key=f"materials.{name}")
    for key in table:
        if key not in _MATERIAL_KEYS:
            raise DesignError(f"unknown key in [materials.{name}]; expected {list(_NUMBER_KEYS)}."
                              + did_you_mean(key, _MATERIAL_KEYS), path=path, key=f"materials.{name}.{key}")
    for key in _REQUIRED_KEYS:
        if key not in table:
            raise DesignError(f"[materials.{name}] needs `{key}`", path=path, key=f"materials.{name}.{key}")
    kwargs = {}
    for key in _NUMBER_KEYS:
        if key in table:
            v = table[key]
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                raise DesignError(f"expected a number, got {v!r}", path=path, key=f"materials.{name}.{key}")
            kwargs[key] = float(v)
    try:
        return Material(name=name, source=str(table.get("source", f"defined in {path or 'the design file'} (no source given)")),
                        **kwargs)
    except DesignError as e:
        raise DesignError(e.detail, path=path, key=f"materials.{name}.{e.key}" if e.key else None) from e


def get_material(name: str, extra: Mapping[str, Material] | None = None, path=None, key=None) -> Material:
    """Look a material up among the user's (``extra``) then the built-in ones."""
    pool = dict(BUILTIN_MATERIALS)
    if extra:
        pool.update(extra)
    if name in pool:
        return pool[name]
    common = COMMON_NAMES.get(str(name).casefold().replace(" ", "_"))
    hint = (f" Did you mean `{common}`?" if common in pool else "") or did_you_mean(name, pool)
    raise DesignError(f"unknown material {name!r}; known: {sorted(pool)}." + hint, path=path, key=key)


#: what a user may call a built-in material (a designer trial wrote material = "carbon")
COMMON_NAMES = {"carbon": "cfrp", "carbon_fibre": "cfrp", "carbon_fiber": "cfrp", "cf": "cfrp", "cfk": "cfrp",
                "steel": "steel_304", "stainless": "steel_304", "stainless_steel": "steel_304",
                "aluminium": "al_6061", "aluminum": "al_6061", "alu": "al_6061", "titanium": "ti_6al4v",
                "ceramic": "alumina"}
