"""The rod as a CAD assembly: named, coloured solids; mass properties from the solids; exports."""
from __future__ import annotations

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.fileio import atomic_write_bytes, atomic_write_json
from rodlab.core.massprops import MassProperties, combine
from rodlab.core.units import kg_m3_to_kg_mm3

from .cadlib import build123d
from .parts import part_colours, part_solids

__all__ = ["RodCad", "build_cad"]

log = logging.getLogger(__name__)


@dataclass
class RodCad:
    """A built rod: its design and one build123d solid per part, in {T} [mm]."""

    design: RodDesign
    solids: dict

    def mass_properties(self) -> dict[Part, MassProperties]:
        """Mass, centre of mass in {T} and inertia about the COM of each part, from the solids."""
        out = {}
        for part, solid in self.solids.items():
            rho = kg_m3_to_kg_mm3(self.design.material_of(part).density_kg_m3)
            c = solid.center()
            out[part] = MassProperties(rho * solid.volume, np.array([c.X, c.Y, c.Z]),
                                       rho * np.array(solid.matrix_of_inertia))
        return out

    def total_mass_properties(self) -> MassProperties:
        return combine(self.mass_properties().values())

    def compound(self):
        """A build123d assembly: one labelled, coloured child per part."""
        bd = build123d()
        children = []
        colours = part_colours(self.design)
        for part, solid in self.solids.items():
            child = bd.Compound([solid], label=str(part), color=bd.Color(*colours[part]))
            children.append(child)
        return bd.Compound(children=children, label=f"rod {self.design.name}")

    # -- exports ---------------------------------------------------------------------------
    def export_step(self, path: str | Path) -> Path:
        """STEP assembly with part names and colours (written atomically)."""
        bd = build123d()
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        tmp = p.with_name(f".{p.name}.part")
        bd.export_step(self.compound(), str(tmp), timestamp="2000-01-01T00:00:00")
        data = tmp.read_bytes()
        tmp.unlink()
        return atomic_write_bytes(p, data)

    def export_stl(self, path: str | Path, tolerance_mm: float = 0.02) -> Path:
        """One STL of the whole rod (binary, written atomically)."""
        bd = build123d()
        p = Path(path)
        p.parent.mkdir(parents=True, exist_ok=True)
        tmp = p.with_name(f".{p.name}.part")
        bd.export_stl(bd.Compound(list(self.solids.values())), str(tmp), tolerance=tolerance_mm)
        data = tmp.read_bytes()
        tmp.unlink()
        return atomic_write_bytes(p, data)

    def mass_report(self) -> dict:
        """``mass.json`` content: per part and total mass_kg, com_T_mm, inertia_kg_mm2."""
        parts = {str(p): m.to_dict() for p, m in self.mass_properties().items()}
        for p, name in zip(self.solids, parts):
            parts[name]["material"] = self.design.material_of(p).name
            parts[name]["volume_mm3"] = float(self.solids[p].volume)
        return {"format": "rodlab.mass/1", "rod": self.design.name,
                "frame": "T (origin at the ball centre, axes of the flange frame {6})",
                "parts": parts, "total": self.total_mass_properties().to_dict()}

    def write_mass_json(self, path: str | Path) -> Path:
        return atomic_write_json(path, self.mass_report())


def build_cad(design: RodDesign) -> RodCad:
    """Build the CAD assembly of ``design`` (raises :class:`~geometry.errors.GeometryError` if impossible)."""
    return RodCad(design, part_solids(design))
