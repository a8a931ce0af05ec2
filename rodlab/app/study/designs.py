"""The designs a study compares: an L1 x L2 grid around a base (with tube-material and tube-size variants) or a
list of design files; an invalid combination is a candidate with its reason, never fatal."""
from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass, replace
from pathlib import Path

from rodlab.core.design import RodDesign
from rodlab.core.design_range import check_design
from rodlab.core.errors import RodlabError
from rodlab.core.materials import get_material

__all__ = ["Candidate", "grid_candidates", "list_candidates", "parse_tube", "check_variants", "r_prior_of", "R_PRIOR_METAL",
           "R_PRIOR_COMPOSITE", "R_PRIOR_AS_BUILT", "is_as_built"]

#: true / simulated compliance of a built rod (paper Table 2): stainless steel 1.01-1.05, carbon 1.23-2.30
R_PRIOR_METAL = (1.01, 1.05)
R_PRIOR_COMPOSITE = (1.23, 2.30)
#: r_rod of a design ``rodlab update`` wrote from a measurement: the measurement is in its moduli, what is left is
#: the rig's remounting and refit (1 %, 1 sigma: docs/diagnose.md), here +-2 %
R_PRIOR_AS_BUILT = (0.98, 1.02)
#: the first line ``rodlab update`` writes in an as-built design file
AS_BUILT_HEADER = "# as built: rodlab update"


@dataclass(frozen=True)
class Candidate:
    """One design of a study: ``design`` (None when ``invalid`` says why), its L1 / L2 [mm], tube material and
    size (``OD x wall`` [mm]) for the table."""

    label: str
    L1_mm: float
    L2_mm: float
    material: str
    tube: str
    design: RodDesign | None = None
    invalid: str = ""


def parse_tube(text: str) -> tuple[float, float]:
    """``ODxWALL`` [mm], e.g. ``25x2``."""
    m = re.fullmatch(r"\s*([0-9.]+)\s*[xX*]\s*([0-9.]+)\s*", text)
    if not m:
        raise RodlabError(f"--tubes {text!r}: expected OUTERxWALL in mm, e.g. 25x2")
    return float(m.group(1)), float(m.group(2))


def _describe(d: RodDesign) -> tuple[str, str]:
    t = d.pipe_I
    return t.material.name, f"{t.outer_diameter_mm:g}x{t.wall_mm:g}"


def _with_tube(base: RodDesign, material: str | None, tube: tuple[float, float] | None) -> RodDesign:
    """``base`` with pipes I and II of another material and / or size (the bend, rings and holder follow the
    size: same wall as the tubes, the bend's radius in the same ratio to its diameter, sleeves as much wider as
    before; a new-user trial's 45 mm variants of a 32 mm rod had kept its 60 mm bend radius, below the rule's 1.5
    diameters, and were all invalid)."""
    kw = {}
    if material is not None:
        mat = get_material(material, {m.name: m for m in (base.pipe_I.material, base.pipe_II.material)},
                           key="materials")
        kw = {"pipe_I": replace(base.pipe_I, material=mat), "pipe_II": replace(base.pipe_II, material=mat)}
    d = replace(base, **kw) if kw else base
    if tube is None:
        return d
    od, wall = tube
    grow = od - d.pipe_I.outer_diameter_mm
    return replace(d, pipe_I=replace(d.pipe_I, outer_diameter_mm=od, wall_mm=wall),
                   pipe_II=replace(d.pipe_II, outer_diameter_mm=od, wall_mm=wall),
                   bend=replace(d.bend, outer_diameter_mm=od, wall_mm=wall,
                                radius_mm=d.bend.radius_mm * od / d.bend.outer_diameter_mm),
                   rings=replace(d.rings, outer_diameter_mm=d.rings.outer_diameter_mm + grow),
                   pipe_holder=replace(d.pipe_holder, outer_diameter_mm=d.pipe_holder.outer_diameter_mm + grow))


def grid_candidates(base: RodDesign, L1s, L2s, materials=(None,), tubes=(None,)) -> list[Candidate]:
    """Every L1 x L2 x material x tube variant of ``base``."""
    out = []
    for mat in materials or (None,):
        for tube in tubes or (None,):
            for L1 in L1s:
                for L2 in L2s:
                    out.append(_candidate(base, float(L1), float(L2), mat, tube))
    return out


def check_variants(base: RodDesign, materials=(None,), tubes=(None,), L1s=(), L2s=()) -> None:
    """Refuse ``--materials`` or ``--tubes`` whose every value makes no rod of ``base``'s lengths (a material not
    known, a wall no less than the radius, a tube so thin the rod would hang: a size in cm), naming the option and
    the value, before a study runs (a new-user trial: each had run, written its pages as "no design usable" and
    exited with an error; the size in cm had read `ComplianceError: key C_F_mm_per_N`). Where some values make
    rods, the others are candidates with their reason, as any invalid combination is."""
    for option, values in (("--materials", [(m, None) for m in materials if m]),
                           ("--tubes", [(None, t) for t in tubes if t])):
        failed = []
        for mat, tube in values:
            e = _fails_everywhere(base, mat, tube, list(L1s) or [base.L1_mm], list(L2s) or [base.L2_mm])
            if e is not None:
                failed.append((mat or f"{tube[0]:g}x{tube[1]:g}", e))
        if values and len(failed) == len(values):
            value, e = failed[0]
            raise RodlabError(f"{option} {value}: {getattr(e, 'detail', str(e))} (at every L1 x L2 of the "
                              "study)") from e


def _fails_everywhere(base: RodDesign, mat, tube, L1s, L2s) -> RodlabError | None:
    """The first error of the variant (``mat``, ``tube``) of ``base`` where it makes no rod at any of the lengths
    (a review: a thin tube refused on the base's lengths was a rod on the shorter ones of the grid), else None."""
    first = None
    for L1 in L1s:
        for L2 in L2s:
            try:
                check_design(replace(_with_tube(base, mat, tube), L1_mm=float(L1), L2_mm=float(L2)))
                return None
            except RodlabError as e:
                first = first or e
    return first


def _candidate(base, L1, L2, mat, tube) -> Candidate:
    label = f"{base.name} {L1:g}-{L2:g}" + (f" {mat}" if mat else "") + (f" {tube[0]:g}x{tube[1]:g}" if tube else "")
    try:
        d = replace(_with_tube(base, mat, tube), L1_mm=L1, L2_mm=L2, name=label)
        check_design(d)                   # a rod that would hang is no candidate (its reason, not a compliance's)
    except RodlabError as e:
        m = mat or base.pipe_I.material.name
        t = f"{tube[0]:g}x{tube[1]:g}" if tube else _describe(base)[1]
        return Candidate(label, L1, L2, m, t, None, str(e))
    return Candidate(label, L1, L2, *_describe(d), d)


def list_candidates(designs: list[RodDesign]) -> list[Candidate]:
    """One candidate per design (e.g. the six paper rods), labelled by its name; designs that share a name (a rod
    and its as-built design from ``rodlab update``, a paper trial) by name and file, and by their place in the list
    where even that repeats."""
    twice = {n for n, k in Counter(d.name for d in designs).items() if k > 1}
    labels = [_label(d, d.name in twice) for d in designs]
    repeated = {lb for lb, k in Counter(labels).items() if k > 1}
    labels = [f"{lb} #{i + 1}" if lb in repeated else lb for i, lb in enumerate(labels)]
    return [Candidate(lb, d.L1_mm, d.L2_mm, *_describe(d), d) for lb, d in zip(labels, designs)]


def _label(design: RodDesign, shared: bool) -> str:
    if not shared:
        return design.name
    return f"{design.name} ({Path(design.source).name if design.source else 'built in'})"


def is_as_built(design: RodDesign) -> bool:
    """Whether ``design``'s file was written by ``rodlab update`` from a measurement: its header line among the
    comment lines that open the file (a user's comment above it is allowed)."""
    if not design.source:
        return False
    try:
        with open(design.source, encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith(AS_BUILT_HEADER):
                    return True
                if line.strip() and not line.lstrip().startswith("#"):
                    return False
    except OSError:
        return False
    return False


def r_prior_of(design: RodDesign, metal=R_PRIOR_METAL, composite=R_PRIOR_COMPOSITE) -> tuple[float, float]:
    """The r_rod prior of a design: :data:`R_PRIOR_AS_BUILT` for an as-built design (:func:`is_as_built`: its
    measurement is in it, a paper trial had it counted twice), else ``composite`` when its tubes are anisotropic
    (carbon), else ``metal``."""
    if is_as_built(design):
        return R_PRIOR_AS_BUILT
    iso = design.pipe_I.material.is_isotropic and design.pipe_II.material.is_isotropic
    return tuple(metal) if iso else tuple(composite)
