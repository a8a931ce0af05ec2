"""Read ``*.rod.toml`` rod designs (contract ``rodlab.rod/1``; ``rodlab.rod/2`` adds ``[joints.PLACE]``, compliant
joints the design declares: :mod:`rodlab.core.joint_springs`) and the built-in designs.

Defaults for optional parts (documented in ``docs/formats.md``; ``OD`` = pipe I's outer diameter):

=============  ========================================================================
``[bend]``     the tube itself, bent: pipe I's material, OD and wall; ``radius_mm = 2 OD``
``[rings]``    ``al_7075``, ``outer_diameter_mm = OD + 6``, ``length_mm = 2 OD``
``[pipe_holder]`` ``al_7075``, ``outer_diameter_mm = OD + 15``, ``length_mm = 40``
``[ball_holder]`` ``al_7075``, ``outer_diameter_mm = min(0.8 OD, 0.7 ball)``, ``length_mm = 20``
``[ball]``     ``alumina``, ``diameter_mm = 30``
=============  ========================================================================

``[pipe_I]`` and ``[pipe_II]`` override any key of ``[tube]``. A ``[bend]`` with only
``radius_mm`` takes material, OD and wall from pipe I. ``length_mm = 0`` removes a part.
"""
from __future__ import annotations

import logging
import math
import re
from dataclasses import replace
from collections.abc import Mapping
from importlib import resources
from pathlib import Path

from .design import BallSpec, BendSpec, RodDesign, SleeveSpec, TubeSpec
from .errors import DesignError, FormatError, did_you_mean
from .fileio import read_toml
from .joint_springs import JOINT_KEYS, JOINT_PLACES, JointSpring
from .materials import Material, get_material, material_from_table
from .tolerances import check_tolerance_table
from .schema import require_schema
from .design_range import check_design, laminate_bend_warning, range_warnings

__all__ = ["load_design", "design_from_dict", "design_to_dict", "builtin_designs", "resolve_design", "FORMAT_ROD",
           "FORMAT_ROD_V2", "ROD_FORMATS"]

FORMAT_ROD = "rodlab.rod/1"
#: v2: a design that declares compliant joints (``[joints.PLACE]``); a file without them stays v1
FORMAT_ROD_V2 = "rodlab.rod/2"
ROD_FORMATS = (FORMAT_ROD, FORMAT_ROD_V2)

log = logging.getLogger(__name__)

_TOP_KEYS = ("format", "name", "L1_mm", "L2_mm", "gamma_deg", "tube", "pipe_I", "pipe_II", "ball",
             "bend", "rings", "pipe_holder", "ball_holder", "materials", "tolerances", "joints")
_TUBE_KEYS = ("material", "outer_diameter_mm", "wall_mm")
_BEND_KEYS = ("material", "outer_diameter_mm", "wall_mm", "radius_mm")
_SLEEVE_KEYS = ("material", "outer_diameter_mm", "length_mm")
_BALL_KEYS = ("material", "diameter_mm")


def _line_of(text: str | None, table: str | None, key: str | None) -> int | None:
    """1-based line of ``key = ...`` inside ``[table]`` (or of the table header), if found."""
    if not text:
        return None
    current = None
    header_line = None
    for i, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        m = re.match(r"^\[\s*([^\]]+?)\s*\]$", line)
        if m:
            current = m.group(1).strip()
            if table is not None and current == table:
                header_line = i
                if key is None:
                    return i
            continue
        if key is not None and current == table and re.match(rf"^(\"|')?{re.escape(_unquote(key))}(\"|')?\s*=", line):
            return i
    return header_line


def _line_of_key(text: str | None, dotted: str | None) -> int | None:
    """:func:`_line_of` for a dotted key: ``tube.outer_diameter_mm`` in ``[tube]``, ``L2_mm`` at the top."""
    table, _, key = (dotted or "").rpartition(".")
    return _line_of(text, table or None, key or None)


def _unquote(key: str) -> str:
    """A TOML key as written without its quotes (``"tube.wall_mm"`` -> ``tube.wall_mm``)."""
    return key[1:-1] if len(key) > 1 and key[0] == key[-1] and key[0] in "\"'" else key


class _Ctx:
    """Carries file path and text so every error names file, line and key."""

    def __init__(self, path, text):
        self.path = path
        self.text = text

    def err(self, msg: str, table: str | None, key: str | None, cls=DesignError, also=()) -> DesignError:
        full_key = f"{table}.{key}" if table and key else (table or key)
        return cls(msg, path=self.path, line=_line_of(self.text, table, key), key=full_key, also=also)

    def locate(self, e: FormatError) -> FormatError:
        """``e`` (and the problems in its ``also``) with this file and the line of its key, unless located."""
        if e.path is not None or self.path is None:
            return e
        t, _, k = (e.key or "").rpartition(".")
        return self.err(e.detail, t or None, k or None, type(e), also=[self.locate(a) for a in e.also])

    def number(self, tbl: Mapping, table: str | None, key: str, default=None) -> float:
        if key not in tbl:
            if default is None:
                raise self.err(f"missing required key `{key}`", table, None)
            return float(default)
        v = tbl[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise self.err(f"expected a number, got {v!r}", table, key)
        v = float(v)
        if not math.isfinite(v):
            raise self.err(f"expected a finite number, got {v!r}", table, key)
        if v < 0:
            raise self.err(f"expected a non-negative number, got {v!r}", table, key)
        return v

    def check_keys(self, tbl, table: str | None, allowed) -> None:
        if not isinstance(tbl, Mapping):
            raise self.err(f"expected a table, got {type(tbl).__name__}", table, None)
        for k in tbl:
            if k not in allowed:
                where = f"[{table}]" if table else "the top level"
                raise self.err(f"unknown key `{k}` in {where}; allowed: {list(allowed)}." + did_you_mean(k, allowed),
                               table, k)

    def material(self, name, table: str, materials: Mapping[str, Material]) -> Material:
        if not isinstance(name, str):
            raise self.err(f"material must be a name (string), got {name!r}", table, "material")
        try:
            return get_material(name, materials)
        except DesignError as e:
            raise self.err(str(e), table, "material") from e


def design_from_dict(data: Mapping, path: str | Path | None = None, text: str | None = None) -> RodDesign:
    """Build a validated :class:`RodDesign` from parsed TOML (errors name file, line and key)."""
    c = _Ctx(None if path is None else str(path), text)
    try:
        return _build(data, c, path)
    except FormatError as e:
        located = c.locate(e)
        if located is e:
            raise
        raise located from e


def _build(data: Mapping, c: _Ctx, path) -> RodDesign:
    c.check_keys(data, None, _TOP_KEYS)
    fmt = data.get("format")
    if fmt not in ROD_FORMATS:
        raise c.err(f"expected format = \"{FORMAT_ROD}\" (or \"{FORMAT_ROD_V2}\" with [joints]), got {fmt!r}", None,
                    "format", FormatError)
    if "joints" in data and fmt != FORMAT_ROD_V2:
        raise c.err(f"a [joints] table needs format = \"{FORMAT_ROD_V2}\" (a {FORMAT_ROD} reader would not know it); "
                    "change the format line", None, "format", FormatError)
    name = data.get("name", Path(str(path)).name.split(".")[0] if path else "rod")
    if not isinstance(name, str) or not name.strip():
        raise c.err(f"name must be a non-empty string, got {name!r}", None, "name")
    materials = _materials(data, c)
    L1 = c.number(data, None, "L1_mm")
    L2 = c.number(data, None, "L2_mm")
    gamma = c.number(data, None, "gamma_deg")
    if "tube" not in data and not ("pipe_I" in data and "pipe_II" in data):
        raise c.err("missing [tube] (or both [pipe_I] and [pipe_II])", None, "tube")
    c.check_keys(data.get("tube", {}), "tube", _TUBE_KEYS)
    try:
        parts = _parts(data, c, materials)
    except FormatError as e:               # the design's own numbers in other units are said beside it
        hints = _unit_hints(L1, L2, gamma, c)
        if not hints:
            raise
        raise type(e)(e.detail, e.path, e.line, e.key, also=(*e.also, *hints)) from None
    design = RodDesign(name.strip(), L1, L2, gamma, parts["pipe_I"], parts["pipe_II"], parts["bend"], parts["rings"],
                       parts["pipe_holder"], parts["ball_holder"], parts["ball"],
                       source=None if path is None else Path(path), joints=_joints(data.get("joints", {}), c))
    return _with_tolerances(design, data.get("tolerances", {}), c)


def _unit_hints(L1: float, L2: float, gamma: float, c: _Ctx) -> list[DesignError]:
    """A bend angle that looks like radians, lengths that look like metres: the design rules say so too, but only
    once the parts are read; a part's problem (an unknown material) had hidden them (a designer trial)."""
    out = []
    if 0 < gamma <= math.pi:
        out.append(c.err(f"gamma_deg = {gamma:g} looks like radians ({gamma:g} rad = {math.degrees(gamma):.1f} deg): "
                         "gamma_deg is in degrees", None, "gamma_deg"))
    for key, v in (("L1_mm", L1), ("L2_mm", L2)):
        if 0 < v < 5.0:
            out.append(c.err(f"{key} = {v:g} looks like metres ({v:g} m = {1000 * v:g} mm): lengths are in "
                             "millimetres", None, key))
    return out


def _parts(data: Mapping, c: _Ctx, materials: dict) -> dict:
    """The design's parts by table name, every part checked before any error is raised: the first problem leads
    and the others come in its ``also`` (a part whose defaults come from a broken one is not checked)."""
    parts: dict = {}
    problems: list[FormatError] = []

    def attempt(label: str, make, *needs: str) -> None:
        if all(parts.get(n) is not None for n in needs):
            try:
                parts[label] = make()
                return
            except FormatError as e:
                e = c.locate(e)
                if all(str(e) != str(p) for p in problems):       # [tube]'s own error, met by both pipes
                    problems.append(e)
        parts[label] = None

    def od() -> float:
        return parts["pipe_I"].outer_diameter_mm
    attempt("pipe_I", lambda: _tube(data, c, "pipe_I", materials))
    attempt("pipe_II", lambda: _tube(data, c, "pipe_II", materials))
    attempt("ball", lambda: _ball(data, c, materials))
    own_section = isinstance(data.get("bend"), Mapping) and {"material", "outer_diameter_mm", "wall_mm"} <= set(data["bend"])
    attempt("bend", lambda: _bend(data, c, parts["pipe_I"], materials), *(() if own_section else ("pipe_I",)))
    attempt("rings", lambda: _sleeve(data, c, "rings", materials, "al_7075", od() + 6.0, 2.0 * od()), "pipe_I")
    attempt("pipe_holder", lambda: _sleeve(data, c, "pipe_holder", materials, "al_7075", od() + 15.0, 40.0), "pipe_I")
    attempt("ball_holder", lambda: _sleeve(data, c, "ball_holder", materials, "al_7075",
                                           min(0.8 * parts["pipe_II"].outer_diameter_mm,
                                               0.7 * parts["ball"].diameter_mm), 20.0), "pipe_II", "ball")
    if problems:
        first = problems[0]
        raise type(first)(first.detail, first.path, first.line, first.key, also=problems[1:])
    return parts


def _ball(data: Mapping, c: _Ctx, materials: dict) -> BallSpec:
    ball_t = data.get("ball", {})
    c.check_keys(ball_t, "ball", _BALL_KEYS)
    return BallSpec(c.material(ball_t.get("material", "alumina"), "ball", materials),
                    c.number(ball_t, "ball", "diameter_mm", 30.0))


def _joints(table, c: _Ctx) -> dict[str, JointSpring]:
    """The ``[joints.PLACE]`` tables (v2): {place: spring}, places and keys checked."""
    if not isinstance(table, Mapping):
        raise c.err(f"expected [joints.PLACE] tables, got {type(table).__name__}", None, "joints")
    out = {}
    for place, tbl in table.items():
        if place not in JOINT_PLACES:
            raise c.err(f"unknown joint place `{place}`; places: {list(JOINT_PLACES)}." +
                        did_you_mean(place, JOINT_PLACES), f"joints.{place}", None)
        c.check_keys(tbl, f"joints.{place}", JOINT_KEYS)
        if not tbl:
            raise c.err(f"expected at least one of {list(JOINT_KEYS)} [rad/(N m)]", f"joints.{place}", None)
        values = {k: c.number(tbl, f"joints.{place}", k) for k in tbl}
        try:
            out[place] = JointSpring(**values)
        except DesignError as e:
            raise c.err(e.detail, f"joints.{place}", e.key) from e
    return out


def _with_tolerances(design: RodDesign, table, c: _Ctx) -> RodDesign:
    """``design`` with its ``[tolerances]`` table, every key checked against the design (v1.1)."""
    if not table:
        return design
    if not isinstance(table, Mapping):
        raise c.err(f"expected a table, got {type(table).__name__}", "tolerances", None)
    design = replace(design, tolerances=dict(table))
    try:
        check_tolerance_table(design, design.tolerances)
    except DesignError as e:
        located = [_tolerance_error(x, c) for x in (e, *e.also)]     # every problem of the table, each at its line
        first = located[0]
        raise c.err(first.detail, "tolerances", _quoted(e.key), also=located[1:]) from e
    return design


def _quoted(key: str | None) -> str:
    """A ``tolerances.KEY`` error's key as the table spells it (a dotted key in quotes)."""
    key = (key or "").removeprefix("tolerances.")
    return f'"{key}"' if "." in key else key


def _tolerance_error(e: DesignError, c: _Ctx) -> DesignError:
    return c.err(e.detail, "tolerances", _quoted(e.key))


def _materials(data: Mapping, c: _Ctx) -> dict[str, Material]:
    """The design's own materials (``[materials.NAME]`` tables), by name."""
    materials: dict[str, Material] = {}
    mats = data.get("materials", {})
    c.check_keys(mats, "materials", list(mats) if isinstance(mats, Mapping) else [])
    for mname, mtable in mats.items():
        try:
            materials[mname] = material_from_table(mname, mtable)
        except DesignError as e:
            sub = e.key.split(".")[-1] if e.key and e.key.count(".") >= 2 else None
            raise c.err(e.detail, f"materials.{mname}", sub) from e
    return materials


def _tube(data: Mapping, c: _Ctx, label: str, materials: dict) -> TubeSpec:
    """Pipe ``label``: ``[tube]`` with ``[label]``'s keys over it; errors name the table the value came from."""
    over = data.get(label, {})
    c.check_keys(over, label, _TUBE_KEYS)
    merged = dict(data.get("tube", {}))
    merged.update(over)
    src = label if any(k in over for k in _TUBE_KEYS) else "tube"
    for k in _TUBE_KEYS:
        if k not in merged:
            raise c.err(f"missing `{k}` for {label} (give it in [tube] or [{label}])", "tube", None)
    tbl = label if "material" in over else "tube"
    mat = c.material(merged["material"], tbl, materials)
    od = c.number(merged, label if "outer_diameter_mm" in over else "tube", "outer_diameter_mm")
    wall = c.number(merged, label if "wall_mm" in over else "tube", "wall_mm")
    return TubeSpec(mat, od, wall, key=label if "wall_mm" in over else src)


def _bend(data: Mapping, c: _Ctx, p1: TubeSpec | None, materials: dict) -> BendSpec:
    """The bend: pipe I's material and section unless ``[bend]`` says otherwise; radius 2 x its diameter.
    ``p1`` None (pipe I is broken): ``[bend]`` must give its material and section itself."""
    bend_t = data.get("bend", {})
    c.check_keys(bend_t, "bend", _BEND_KEYS)
    bend_mat = c.material(bend_t["material"], "bend", materials) if "material" in bend_t else p1.material
    bod = c.number(bend_t, "bend", "outer_diameter_mm", p1.outer_diameter_mm if p1 else None)
    bwall = c.number(bend_t, "bend", "wall_mm", p1.wall_mm if p1 else None)
    brad = c.number(bend_t, "bend", "radius_mm", 2.0 * bod)
    return BendSpec(bend_mat, bod, bwall, key="bend", radius_mm=brad)


def _sleeve(data: Mapping, c: _Ctx, label: str, materials: dict, dflt_mat: str, dflt_od: float,
            dflt_len: float) -> SleeveSpec:
    """A sleeve-like part (rings, holders) from ``[label]`` with the given defaults."""
    t = data.get(label, {})
    c.check_keys(t, label, _SLEEVE_KEYS)
    mat = c.material(t["material"], label, materials) if "material" in t else get_material(dflt_mat)
    return SleeveSpec(mat, c.number(t, label, "outer_diameter_mm", dflt_od),
                      c.number(t, label, "length_mm", dflt_len), key=label)


def design_to_dict(design: RodDesign) -> dict:
    """``design`` as a ``rodlab.rod/1`` table that :func:`design_from_dict` reads back to an equal design: every
    part explicit (``length_mm = 0`` for an absent one) and every material's numbers in ``[materials]`` (so a
    file written today keeps its meaning if a built-in material is revised)."""
    mats: dict[str, dict] = {}

    def mat(m) -> str:
        t = {"E_GPa": m.E_GPa, "nu": m.nu, "density_kg_m3": m.density_kg_m3}
        t.update({k: getattr(m, k) for k in ("E_transverse_GPa", "G_GPa", "cte_ppm_K", "strength_MPa",
                                             "shear_strength_MPa") if getattr(m, k) is not None})
        mats[m.name] = t
        return m.name

    def tube(t) -> dict:
        return {"material": mat(t.material), "outer_diameter_mm": t.outer_diameter_mm, "wall_mm": t.wall_mm}

    def sleeve(t) -> dict:
        return {"material": mat(t.material), "outer_diameter_mm": t.outer_diameter_mm, "length_mm": t.length_mm}
    d = design
    out = {"format": FORMAT_ROD_V2 if d.joints else FORMAT_ROD, "name": d.name, "L1_mm": d.L1_mm, "L2_mm": d.L2_mm,
           "gamma_deg": d.gamma_deg, "pipe_I": tube(d.pipe_I), "pipe_II": tube(d.pipe_II),
           "bend": dict(tube(d.bend), radius_mm=d.bend.radius_mm), "rings": sleeve(d.rings),
           "pipe_holder": sleeve(d.pipe_holder), "ball_holder": sleeve(d.ball_holder),
           "ball": {"material": mat(d.ball.material), "diameter_mm": d.ball.diameter_mm}, "materials": mats}
    if d.joints:
        out["joints"] = {place: {k: getattr(j, k) for k in JOINT_KEYS} for place, j in d.joints.items()}
    return out


def load_design(path: str | Path, *, schema: bool = True) -> RodDesign:
    """Read and validate a ``*.rod.toml`` file: the design's own rules, then :mod:`rodlab.core.design_range` (a rod
    that would hang is refused; keys outside the checked range are logged as warnings with file and line).
    ``schema=False`` skips the JSON Schema pass (the built-in designs: rodlab's own files, checked against it by
    its tests; jsonschema's import is ~0.15 s of every command's start)."""
    p = Path(path)
    data, text = read_toml(p, FormatError)
    design = design_from_dict(data, p, text)
    if schema:
        require_schema(data, str(data.get("format")), p, text, FormatError, kind="toml")   # anything the rules miss
    try:
        check_design(design)
    except DesignError as e:
        raise DesignError(e.detail, path=p, line=_line_of_key(text, e.key), key=e.key, also=e.also) from e
    for w in range_warnings(design):
        line = _line_of_key(text, w.key)
        log.warning("%s%s, %s", p, f", line {line}" if line else "", w.describe())
    bend = data.get("bend") if isinstance(data.get("bend"), Mapping) else {}
    if (said := laminate_bend_warning(design, "material" in bend)) is not None:
        log.warning("%s: %s", p, said)
    return design


def builtin_designs() -> dict[str, Path]:
    """Built-in designs shipped with rodlab: the six rods of the paper's Table 2 (``rod1`` .. ``rod6``)."""
    folder = resources.files("rodlab") / "data" / "rods"
    return {Path(str(f)).name.split(".")[0]: Path(str(f)) for f in folder.iterdir()
            if str(f).endswith(".rod.toml")}


def resolve_design(spec: str | Path) -> RodDesign:
    """Load ``spec`` as a file path or, when no such file exists, as a built-in name (``rod1``, ``1#``)."""
    p = Path(spec)
    names = builtin_designs()
    key = str(spec).strip()
    alias = {f"{k[3:]}#": k for k in names if k.startswith("rod")}
    key = alias.get(key, key)
    if p.is_file() or (str(spec).endswith(".toml") and not p.exists()):
        return load_design(p)
    if key in names:                    # a folder named like a built-in (rod1/) does not hide it
        if p.exists():
            log.warning("%s: the built-in design %s, not the folder %s/ here (a folder is not a design file)",
                        spec, key, spec)
        return load_design(names[key], schema=False)
    if p.exists():
        return load_design(p)
    raise FormatError(f"no such file or built-in design; built-ins: {sorted(names)}." + did_you_mean(key, names),
                      path=spec)
