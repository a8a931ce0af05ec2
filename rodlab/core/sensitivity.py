"""How a rod's compliance moves with its uncertain keys, and how far a simulation method is from the rod.

- :func:`with_values`: the design with some dotted keys set (a rod as built); :func:`scale_moduli`: every modulus
  times one factor (a rod uniformly softer or stiffer);
- :func:`compliance_sensitivity`: C_F and its derivatives with respect to design keys (central differences on a
  compliance model: the closed form here, the frame model when the application passes it);
- :data:`METHOD_ACCURACY`: the bias, scatter and correlation of a simulation method's C_F entries against the solid
  FEA, from rodlab's own verification set (``fea/data/solid_reference.json``: docs/diagnose.md;
  ``tests/test_tolerances.py`` recomputes it).
"""
from __future__ import annotations

import copy
import tomllib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .design import RodDesign
from .design_io import FORMAT_ROD_V2, design_from_dict, design_to_dict
from .errors import DesignError
from .tolerances import design_value

__all__ = ["with_values", "scale_moduli", "MODULUS_KEYS", "MODULI", "compliance_sensitivity", "Sensitivity", "METHOD_ACCURACY",
           "STRUCTURAL_ENTRIES", "method_accuracy", "MethodAccuracy"]

#: the C_F entries a planar rod has (x, z in its plane, y out of it): (m, n) with m <= n
STRUCTURAL_ENTRIES = ((0, 0), (0, 2), (1, 1), (2, 2))

@dataclass(frozen=True)
class MethodAccuracy:
    """How a simulation method's C_F entries (:data:`STRUCTURAL_ENTRIES`, in that order) sit against the solid FEA:
    ln(method / solid) has mean ``bias`` and standard deviation ``sd`` with correlation ``corr`` [-].

    bias, sd : shape=(4,); corr : shape=(4, 4); label : the method's name
    """

    label: str
    bias: np.ndarray
    sd: np.ndarray
    corr: np.ndarray

    def __post_init__(self) -> None:
        for name, shape in (("bias", (4,)), ("sd", (4,)), ("corr", (4, 4))):
            object.__setattr__(self, name, np.asarray(getattr(self, name), float))
            if getattr(self, name).shape != shape:
                raise ValueError(f"MethodAccuracy.{name}: shape {shape} expected, got {getattr(self, name).shape}")

    @classmethod
    def uniform(cls, label: str, rel: float) -> "MethodAccuracy":
        """No bias, ``rel`` on every entry, independent (a stated accuracy)."""
        return cls(label, np.zeros(4), np.full(4, rel), np.eye(4))

    def _index(self, entries) -> list:
        return [STRUCTURAL_ENTRIES.index(tuple(e)) for e in entries]

    def expected(self, C_sim: np.ndarray, entries) -> np.ndarray:
        """The rod's entries a simulation ``C_sim`` predicts once the method's bias is removed [mm/N]."""
        i = self._index(entries)
        return np.array([C_sim[m, n] for m, n in entries]) * np.exp(-self.bias[i])

    def covariance(self, C_sim: np.ndarray, entries) -> np.ndarray:
        """Covariance of those entries from the method's scatter [(mm/N)^2]."""
        i = self._index(entries)
        scale = np.abs(np.array([C_sim[m, n] for m, n in entries])) * self.sd[i]
        return self.corr[np.ix_(i, i)] * np.outer(scale, scale)


#: ln(method / solid FEA) of the C_F entries c11, c13, c22, c33 over rodlab's 60 bent solid references (rod1-rod6,
#: full rods A-Z, part probes, thin bends, families; ``fea/data/solid_reference.json``; ``tests/test_tolerances.py``
#: recomputes it). The closed form is stiffer (no shear, rigid joints, no bend ovalisation) by 6-17 % on average,
#: scattering 3-22 %; the calibrated frame has no bias and ~1 % scatter. The solid FEA: 1 % per entry, its
#: discretisation (~0.2 % on the default mesh, 0.5 % against an order-1 reference on the derived rod 1#, whose
#: sleeves' corners converge slowly) and its idealised geometry (perfect bonds, sharp corners, no adhesive layer:
#: a rod as built, or another code's model of it, differs from it by that much without a joint; a new-user trial's
#: own 3-D beam model of an as-built rod had been diagnosed as a joint at 0.2 %).
METHOD_ACCURACY = {
    "calc": MethodAccuracy("calc", [-0.094, -0.111, -0.061, -0.169], [0.105, 0.218, 0.033, 0.082],
                           [[1.0, 0.784, 0.255, 0.465], [0.784, 1.0, 0.388, 0.502], [0.255, 0.388, 1.0, 0.771],
                            [0.465, 0.502, 0.771, 1.0]]),
    "frame": MethodAccuracy("frame", [0.0017, -0.0022, 0.0, -0.0011], [0.0089, 0.0094, 0.0059, 0.0129],
                            [[1.0, 0.599, 0.509, 0.619], [0.599, 1.0, 0.595, 0.728], [0.509, 0.595, 1.0, 0.865],
                             [0.619, 0.728, 0.865, 1.0]]),
    "solid": MethodAccuracy.uniform("solid", 0.01),
}


def method_accuracy(method: str, model: str | None = None) -> MethodAccuracy:
    """The accuracy of a compliance file's ``method`` (``calc``, ``fea``) and, for ``fea``, the provenance's
    ``model``: rodlab's ``frame`` or ``solid``, or (none or another name) another code's FEA, whose bias against
    rodlab's solid is unknown: none, with the solid's 1 % per entry (a review: such a file had been given the
    frame's bias, 0.1-0.2 % per entry, as if rodlab's frame had made it)."""
    if method == "calc":
        return METHOD_ACCURACY["calc"]
    if method == "fea":
        if model in ("frame", "solid"):
            return METHOD_ACCURACY[model]
        return MethodAccuracy.uniform("fea (another code)", METHOD_ACCURACY["solid"].sd[0])
    raise DesignError(f"no simulation accuracy for method {method!r} (known: calc, fea)", key="method")


def with_values(design: RodDesign, values: dict) -> RodDesign:
    """``design`` with the dotted keys of ``values`` set, without its tolerances. Where the design was read from a
    file, the keys are set in that file's own tables and every default re-derived, as ``rodlab update -o`` writes
    the as-built file (``tube.*`` then moves the bend that is the tube itself, bent, and the defaults that follow
    the tube: a review found the fitted design and the written file 2-24 % apart in c33 where the defaults had been
    frozen); otherwise in the design's full table (``tube.*`` sets every pipe that shares the tube)."""
    raw = _source_table(design)
    data = raw if raw is not None else design_to_dict(design)
    for key, value in values.items():
        design_value(design, key)                       # names the key when the design has none such
        _set(design, data, key, float(value), raw is not None)
    return design_from_dict(data)


def _set(design: RodDesign, data: dict, key: str, value: float, own_tables: bool) -> None:
    """Set one dotted ``key`` in the design table ``data`` (the file's own tables, or the full one)."""
    table, _, name = key.rpartition(".")
    if table.startswith("joints."):
        data["format"] = FORMAT_ROD_V2
        data.setdefault("joints", {}).setdefault(table.split(".", 1)[1], {})[name] = value
    elif table.startswith("materials."):
        label = table.split(".", 1)[1]
        materials = data.setdefault("materials", {})
        if label not in materials:                      # a built-in material: its full table, then the key
            materials[label] = dict(design_to_dict(design)["materials"][label])
        materials[label][name] = value
    elif table == "tube" and own_tables:
        data["tube"][name] = value
    elif table == "tube":
        for label in ("pipe_I", "pipe_II"):
            if getattr(design, label).key == "tube":
                data[label][name] = value
    elif table:
        data.setdefault(table, {})[name] = value
    else:
        data[name] = value


#: design -> its source file's own table where that reproduces it (path, mtime and design as the key)
_SOURCES: dict = {}


def _source_table(design: RodDesign) -> dict | None:
    """A deep copy of the table of the file ``design`` was read from, without its tolerances, where reading it
    gives ``design`` back; else None (a design built in memory, or changed since it was read)."""
    src = design.source
    if src is None or not Path(src).is_file():
        return None
    key = (str(src), Path(src).stat().st_mtime_ns, id(design))
    if key not in _SOURCES:                            # the design is kept with its table: its id stays its own
        try:
            table = tomllib.loads(Path(src).read_text(encoding="utf-8"))
            table.pop("tolerances", None)
            _SOURCES[key] = (design, table if design_from_dict(copy.deepcopy(table)) == design else None)
        except (OSError, ValueError, DesignError, TypeError):
            _SOURCES[key] = (design, None)
    table = _SOURCES[key][1]
    return None if table is None else copy.deepcopy(table)


#: the keys of a material that are moduli (scaled together by :func:`scale_moduli`)
MODULUS_KEYS = ("E_GPa", "G_GPa", "E_transverse_GPa")
#: ``rodlab update``'s key for one factor of every modulus of the rod (:func:`scale_moduli`; design value 1)
MODULI = "moduli"


def scale_moduli(design: RodDesign, factor: float) -> RodDesign:
    """``design`` with every modulus (:data:`MODULUS_KEYS`) of every material it uses — tubes, bend, rings, holders,
    ball — times ``factor`` [-] and every declared joint's compliance divided by it: the rod uniformly stiffer
    (``factor`` > 1) or softer, each compliance entry of the elastic models divided by ``factor`` (the paper's
    r_rod = 1 / factor where the rod differs that way)."""
    if not np.isfinite(factor) or factor <= 0:
        raise DesignError(f"a modulus factor must be a positive number, got {factor!r}", key="moduli")
    data = design_to_dict(design)
    for table in data["materials"].values():
        for key in MODULUS_KEYS:
            if table.get(key) is not None:
                table[key] = float(table[key]) * float(factor)
    for spring in (data.get("joints") or {}).values():
        for key, value in spring.items():
            if key.startswith("s_") and value is not None:
                spring[key] = float(value) / float(factor)
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
