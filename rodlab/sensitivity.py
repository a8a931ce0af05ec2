"""How a rod's compliance moves with its uncertain keys, and how far a simulation method is from the rod.

- :func:`with_values`: the design with some dotted keys set (a rod as built);
- :func:`compliance_sensitivity`: C_F and its derivatives with respect to design keys (central differences on a
  compliance model: the closed form here, the frame model when the application passes it);
- :data:`METHOD_ACCURACY`: one standard deviation of each C_F entry of a simulation method relative to the solid
  FEA reference, from rodlab's own verification set (``fea/data/solid_reference.json``, 303 entries of the
  reference designs: docs/diagnose.md; ``tests/test_tolerances.py`` recomputes it).
"""
from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .design import RodDesign
from .design_io import design_from_dict, design_to_dict
from .errors import DesignError
from .tolerances import design_value

__all__ = ["with_values", "compliance_sensitivity", "Sensitivity", "METHOD_ACCURACY", "STRUCTURAL_ENTRIES",
           "method_accuracy"]

#: the C_F entries a planar rod has (x, z in its plane, y out of it): (m, n) with m <= n
STRUCTURAL_ENTRIES = ((0, 0), (0, 2), (1, 1), (2, 2))

#: relative standard deviation of the C_F entries (0,0), (0,2), (1,1), (2,2) of each method against the solid FEA:
#: rms over rodlab's solid references (rod1-rod6, full rods A-Z, part probes, thin bends, families). The closed form
#: is stiffer by 5-12 % on average (no shear, rigid joints, no bend ovalisation) and up to 73 % off on thin bends;
#: the calibrated frame is within 1 % rms (4.5 % worst); the solid FEA's discretisation error is ~0.1 %.
METHOD_ACCURACY = {
    "calc": {(0, 0): 0.105, (0, 2): 0.176, (1, 1): 0.060, (2, 2): 0.144},
    "frame": {(0, 0): 0.008, (0, 2): 0.010, (1, 1): 0.005, (2, 2): 0.011},
    "solid": {(0, 0): 0.002, (0, 2): 0.002, (1, 1): 0.002, (2, 2): 0.002},
}


def method_accuracy(method: str, model: str | None = None) -> dict:
    """Relative sigma per entry for a compliance file's ``method`` (``calc``, ``fea``) and, for ``fea``, the
    provenance's ``model`` (``frame`` or ``solid``; unknown: the frame's)."""
    if method == "calc":
        return METHOD_ACCURACY["calc"]
    if method == "fea":
        return METHOD_ACCURACY["solid" if model == "solid" else "frame"]
    raise DesignError(f"no simulation accuracy for method {method!r} (known: calc, fea)", key="method")


def with_values(design: RodDesign, values: dict) -> RodDesign:
    """``design`` with the dotted keys of ``values`` set (``tube.*`` sets every pipe that shares the tube);
    without its tolerances (the keys of a perturbed design are those of :func:`design_to_dict`)."""
    data = design_to_dict(design)
    for key, value in values.items():
        design_value(design, key)                       # names the key when the design has none such
        table, _, name = key.rpartition(".")
        if table.startswith("materials."):
            data["materials"][table.split(".", 1)[1]][name] = float(value)
        elif table == "tube":
            for label in ("pipe_I", "pipe_II"):
                if getattr(design, label).key == "tube":
                    data[label][name] = float(value)
        elif table:
            data[table][name] = float(value)
        else:
            data[name] = float(value)
    return design_from_dict(data)


@dataclass(frozen=True)
class Sensitivity:
    """C_F of a design and its derivatives.

    keys : the dotted keys, shape=(k,); C_F : at the nominal values [mm/N], shape=(3, 3); dC_F : derivative per unit
    of each key [mm/N per key unit], shape=(k, 3, 3)
    """

    keys: tuple
    C_F: np.ndarray
    dC_F: np.ndarray

    def __post_init__(self) -> None:
        if np.shape(self.C_F) != (3, 3) or np.shape(self.dC_F) != (len(self.keys), 3, 3):
            raise ValueError(f"Sensitivity: C_F (3, 3) and dC_F ({len(self.keys)}, 3, 3) expected, got "
                             f"{np.shape(self.C_F)} and {np.shape(self.dC_F)}")


def compliance_sensitivity(design: RodDesign, keys, model: Callable[[RodDesign], np.ndarray],
                           rel_step: float = 0.01) -> Sensitivity:
    """C_F of ``design`` by ``model`` (design -> C_F [mm/N]) and its central-difference derivatives with respect to
    each dotted key (steps of ``rel_step`` of the key's value)."""
    keys = tuple(keys)
    C0 = np.asarray(model(design), float)
    dC = np.zeros((len(keys), 3, 3))
    for i, key in enumerate(keys):
        v = design_value(design, key)
        h = rel_step * abs(v) if v else rel_step
        plus = np.asarray(model(with_values(design, {key: v + h})), float)
        minus = np.asarray(model(with_values(design, {key: v - h})), float)
        dC[i] = (plus - minus) / (2.0 * h)
    return Sensitivity(keys, C0, dC)
