"""rodlab: design, simulate, measure and use long measuring rods for on-site robot calibration (MultiCal).

The core package holds the shared types (rod design, materials, compliance files, frames, units)
and the CLI. Domain packages (``geometry``, ``fea``, ``stiffness_rig``, ``calibrate``) depend on it,
never on each other.
"""
from __future__ import annotations

__version__ = "0.1.0"

from .enums import LoadAxis, Method, Part, Phase  # noqa: E402
from .errors import ComplianceError, DesignError, FormatError, RodlabError  # noqa: E402
from .materials import BUILTIN_MATERIALS, Material, get_material  # noqa: E402
from .design import RodDesign  # noqa: E402
from .design_io import builtin_designs, load_design, resolve_design  # noqa: E402
from .massprops import MassProperties, mass_properties, part_mass_properties  # noqa: E402
from .calc import BendModel, calc_compliance, calc_rod_compliance, paper_compliance  # noqa: E402
from .compliance import RodCompliance, c_rod_um, r_rod, read_compliance, write_compliance  # noqa: E402
from .units import G0  # noqa: E402

__all__ = [
    "__version__", "LoadAxis", "Method", "Part", "Phase",
    "RodlabError", "FormatError", "DesignError", "ComplianceError",
    "Material", "BUILTIN_MATERIALS", "get_material",
    "RodDesign", "load_design", "resolve_design", "builtin_designs",
    "MassProperties", "mass_properties", "part_mass_properties",
    "BendModel", "calc_compliance", "calc_rod_compliance", "paper_compliance",
    "RodCompliance", "c_rod_um", "r_rod", "read_compliance", "write_compliance",
    "G0",
]
