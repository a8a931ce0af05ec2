"""The core of rodlab: the shared types and files every domain package and the application build on — rod designs
and their ``*.rod.toml`` files, materials, the layout and mass properties of a rod, the closed-form compliance,
compliance files, the frames and units of the contract, tolerances and model updating's building blocks, schemas,
errors and progress reporting.

The core imports no domain package (``rodlab.geometry``, ``rodlab.fea``, ``rodlab.stiffness_rig``,
``rodlab.calibrate``) and no part of the application (``rodlab.app``); import-linter keeps it so
(docs/architecture.md). The names below are the stable API, also importable from ``rodlab`` itself.
"""
from __future__ import annotations

from .calc import BendModel, calc_compliance, calc_rod_compliance, paper_compliance
from .compliance import RodCompliance, c_rod_um, r_rod, read_compliance, write_compliance
from .design import RodDesign
from .design_io import builtin_designs, load_design, resolve_design
from .enums import LoadAxis, Method, Part, Phase
from .errors import ComplianceError, DesignError, FormatError, RodlabError
from .massprops import MassProperties, mass_properties, part_mass_properties
from .materials import BUILTIN_MATERIALS, Material, get_material
from .units import G0

__all__ = [
    "LoadAxis", "Method", "Part", "Phase",
    "RodlabError", "FormatError", "DesignError", "ComplianceError",
    "Material", "BUILTIN_MATERIALS", "get_material",
    "RodDesign", "load_design", "resolve_design", "builtin_designs",
    "MassProperties", "mass_properties", "part_mass_properties",
    "BendModel", "calc_compliance", "calc_rod_compliance", "paper_compliance",
    "RodCompliance", "c_rod_um", "r_rod", "read_compliance", "write_compliance",
    "G0",
]
