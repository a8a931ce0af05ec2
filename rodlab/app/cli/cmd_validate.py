"""``rodlab validate``: name a file's format and report every problem at once (schema, then the reader's rules)."""
from __future__ import annotations

import importlib
import logging
import re
import sys
from contextlib import contextmanager
from pathlib import Path

from rodlab.calibrate import read_campaign, read_fixture, read_points, resolve_robot
from rodlab.calibrate.device import read_device
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.probe import fit_fixture, read_probe
from rodlab.calibrate.readings import limit_breaches, point_unit_slips, unit_slips
from rodlab.calibrate.robot_formats import ROBOT_READERS
from rodlab.calibrate.sockets import read_sockets

from ...core.errors import LocatedError
from ...core.schema import ALIASES, FORMATS, FileCheck, Problem, check_file

__all__ = ["register", "READERS", "validate_file"]


def _joints(path) -> int:
    """The number of q-columns of a CSV file's header (the reader's n_joints)."""
    text = Path(path).read_text(encoding="utf-8-sig")
    header = next((ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")), "")
    return max(1, len([h for h in header.split(",") if re.fullmatch(r"\s*q[1-9][0-9]*\s*", h)]))


def _read_campaign(path) -> list[str]:
    """The campaign read, and what in its numbers says a column is in other units (radians, um, metres): what
    ``rodlab calibrate`` refuses without ``--units-checked``."""
    return unit_slips(read_campaign(path, _joints(path)), path)


def _read_points(path) -> list[str]:
    return point_unit_slips(read_points(path, _joints(path)), path)


def _read_sockets(path):
    return read_sockets(path, _joints(path))


def _lazy(module: str, name: str):
    def read(path):
        return getattr(importlib.import_module(module), name)(path)
    return read


#: format id -> the reader whose rules go beyond the schema (None: the schema is all there is); a reader that
#: returns a list returns the problems it found in the numbers (units), each a message with its fix
READERS = {
    "rodlab.rod/1": _lazy("rodlab.core.design_io", "load_design"),
    "rodlab.rod/2": _lazy("rodlab.core.design_io", "load_design"),
    "rodlab.compliance/1": _lazy("rodlab.core.compliance", "read_compliance"),
    "rodlab.compliance/2": _lazy("rodlab.core.compliance", "read_compliance"),
    "rodlab.fixture/1": _lazy("rodlab.calibrate", "read_fixture"),
    "rodlab.fixture/2": _lazy("rodlab.calibrate", "read_fixture"),
    "rodlab.device/1": _lazy("rodlab.calibrate.device", "read_device"),
    "rodlab.device/2": _lazy("rodlab.calibrate.device", "read_device"),
    "rodlab.probe/1": _lazy("rodlab.calibrate.probe", "read_probe"),
    "rodlab.robot/1": _lazy("rodlab.calibrate", "read_robot"),
    "rodlab.robot/2": _lazy("rodlab.calibrate", "read_robot"),
    "rodlab.calibration/1": _lazy("rodlab.calibrate.result", "read_calibration"),
    "rodlab.calibration/2": _lazy("rodlab.calibrate.result", "read_calibration"),
    "rodlab.rigplan/1": _lazy("rodlab.stiffness_rig.config", "read_plan"),
    "rodlab.rigprofile/1": _lazy("rodlab.stiffness_rig.config", "read_profile"),
    "rodlab.rigprofile/2": _lazy("rodlab.stiffness_rig.config", "read_profile"),
    "rodlab.rig/1": _lazy("rodlab.stiffness_rig", "read_recording"),
    "rodlab.campaign/1": _read_campaign,
    "rodlab.points/1": _read_points,
    "rodlab.sockets/1": _read_sockets,
    "rodlab.blind_rig/1": _lazy("rodlab.stiffness_rig.blind", "read_blind_definitions"),
    "rodlab.blind_campaign/1": _lazy("rodlab.calibrate.blind", "read_blind_definitions"),
    "rodlab.diagnosis/1": None,
    "rodlab.points_diagnosis/1": None,
}



def schemaless_robot_formats() -> dict[str, str]:
    """Robot file kinds without a JSON schema (``urdf``), suffix -> format name, from the robot format registry:
    their reader's rules are all there is to check."""
    return {suffix: f.format_id for suffix, f in ROBOT_READERS.items() if f.format_id}


READERS.update({fid: _lazy("rodlab.calibrate", "read_robot") for fid in schemaless_robot_formats().values()})


def _schemaless_format(path, format_id: str | None) -> str | None:
    """The robot format (``urdf``) ``--format`` names, or ``path``'s suffix without ``--format``; else None."""
    kinds = schemaless_robot_formats()
    if format_id is not None:
        return format_id if format_id in kinds.values() else None
    suffixes = [x.lower() for x in Path(path).suffixes]
    if suffixes[-2:] == [".urdf", ".xacro"]:        # its reader says how to expand it
        return kinds.get(".urdf")
    return kinds.get(Path(path).suffix.lower())


def _reader(format_id: str):
    """The reader of a format whose rules go beyond its schema, or None."""
    if format_id in schemaless_robot_formats().values():
        return READERS.get(format_id) or _lazy("rodlab.calibrate", "read_robot")
    return READERS.get(format_id)


def validate_file(path, format_id: str | None = None) -> FileCheck:
    """The schema check of ``path`` and, if it passes, its reader's rules (the schema lists all of its own
    problems; a reader those it found in one pass: a rod design's parts, then its rules, each all at once)."""
    robot_format = _schemaless_format(path, format_id)
    if robot_format is not None:
        check = FileCheck(str(path), robot_format)
    else:
        check = check_file(path, format_id)
    reader = _reader(check.format) if check.ok else None
    if reader is None and _only_tolerance_problems(check):
        reader = _lazy_design_without_schema       # its other tolerances' problems too, in the same pass
    if reader is not None:
        with _warnings_of("rodlab") as warned:
            try:
                found = reader(path)
                if isinstance(found, list):
                    check.problems.extend(Problem(str(path), _without_path(m, path)) for m in found)
            except LocatedError as e:
                seen = {p.key for p in check.problems}
                check.problems.extend(Problem(p.path or str(path), p.detail, p.line, p.key) for p in (e, *e.also)
                                      if _unquoted(p.key) not in seen)
            except ValueError as e:
                check.problems.append(Problem(str(path), str(e)))
        check.warnings = [_without_path(w, path) for w in warned]
    return check


def _only_tolerance_problems(check: FileCheck) -> bool:
    """A rod design whose schema problems are all in its ``[tolerances]`` table: its reader (without the schema)
    still finds the table's other problems (an unknown key beside a malformed value)."""
    return (str(check.format).startswith("rodlab.rod/") and bool(check.problems)
            and all((p.key or "").startswith("tolerances.") for p in check.problems))


def _lazy_design_without_schema(path):
    return importlib.import_module("rodlab.core.design_io").load_design(path, schema=False)


def _unquoted(key: str | None) -> str | None:
    return key.replace('"', "") if key else key


@contextmanager
def _warnings_of(name: str):
    """The WARNING messages the ``name`` logger's tree gives inside the block (a list filled as they come), kept
    from the console: ``validate`` lists them under their file."""
    logger, got = logging.getLogger(name), []

    class _Keep(logging.Handler):
        def emit(self, record):
            got.append(record.getMessage())
    handler, propagate = _Keep(logging.WARNING), logger.propagate
    logger.addHandler(handler)
    logger.propagate = False
    try:
        yield got
    finally:
        logger.removeHandler(handler)
        logger.propagate = propagate


def _without_path(message: str, path) -> str:
    """A reader's warning without the file's own path in front (validate prints it under the file)."""
    for prefix in (f"{path}: ", f"{Path(path).name}: "):
        if message.startswith(prefix):
            return message[len(prefix):]
    return message


#: formats whose rows are joint readings of one robot, and how to read them for ``robot.n`` joints
_ROBOT_CHECKED = {"rodlab.campaign/1": lambda path, n: read_campaign(path, n),
                  "rodlab.points/1": lambda path, n: read_points(path, n)}


def _check_against_robot(check: FileCheck, path, robot) -> None:
    """``--robot``: the file's joint columns against the robot's joints (a problem: the reader's error), its rows
    against the robot's joint limits (warnings, :func:`~calibrate.readings.limit_breaches`)."""
    try:
        data = _ROBOT_CHECKED[check.format](path, robot.n)
    except LocatedError as e:
        check.problems.append(Problem(e.path or str(path), e.detail, e.line, e.key))
        return
    lines = getattr(data, "lines", None)
    check.warnings += [_without_path(w, path) for w in limit_breaches(data.q_deg, lines, robot, path)]


def register(sub) -> None:
    p = sub.add_parser("validate", help="check files against rodlab's formats; every problem at once",
                       description="Names each file's format (its `format` key, its `# format:` line or its "
                                   "suffix) and reports every problem against the format's schema (shipped in "
                                   "rodlab/schemas; docs/formats.md) with file, line, key, what was expected "
                                   "and the fix; a file that passes its schema is then read by its reader, "
                                   "whose own rules (a symmetric C_F, holds that keep their load, ...) it must "
                                   "also pass; its warnings (numbers no rod or robot has: a recording in um, a "
                                   "compliance file in um/N, a robot file in radians) are listed under the file. "
                                   "Exit 0 if every file is valid, 2 otherwise.")
    p.add_argument("files", nargs="+", help="files to check")
    p.add_argument("--robot", default=None, metavar="ROBOT",
                   help="also check campaigns and instrument points against this robot (a built-in name or a robot "
                        "file): their joint columns against its joints, their readings against its joint limits")
    p.add_argument("--format", default=None,
                   choices=sorted(FORMATS) + sorted(ALIASES) + sorted(schemaless_robot_formats().values()),
                   help="check as this format instead of the one the file names")
    p.set_defaults(func=cmd_validate)


def _check_positions(checks: list) -> None:
    """Every valid campaign given beside one valid fixture file: its clamping positions must be the fixture's (a
    problem of the campaign's, as ``rodlab calibrate`` refuses it). More than one fixture: not paired."""
    fixtures = [(f, c) for f, c in checks if c.ok and c.format in ("rodlab.fixture/1", "rodlab.fixture/2")]
    if len(fixtures) != 1:
        return
    fpath = fixtures[0][0]
    have = set(read_fixture(fpath).poses)
    for f, c in checks:
        if c.ok and c.format == "rodlab.campaign/1":
            missing = sorted({int(j) for j in read_campaign(f, _joints(f)).position} - have)
            if missing:
                c.problems.append(Problem(str(f), f"clamping position(s) {missing} have no pose in {fpath} (it has "
                                          f"{sorted(have)}): the fixture file is another campaign's or incomplete",
                                          None, "position", "give the fixture file this campaign was recorded with"))


def _check_probes(checks: list) -> None:
    """Every valid probe file given beside one valid device file: probed with that device's features, as `rodlab
    fixture` fits them (features the device lacks, another unit or device, too few or collinear features at a
    position: problems of the probe file's; a position whose residuals exceed the accuracy, swapped labels:
    warnings). More than one device file: not paired."""
    devices = [f for f, c in checks if c.ok and c.format in ("rodlab.device/1", "rodlab.device/2")]
    if len(devices) != 1:
        return
    device = read_device(devices[0])
    device_check = next(c for f, c in checks if f == devices[0])
    for f, c in checks:
        if not (c.ok and c.format == "rodlab.probe/1"):
            continue
        probes = read_probe(f)
        try:
            fit = fit_fixture(probes, device, int(probes.position[0]))
        except CalibrationError as e:           # a fault of the device file is the device file's (a review)
            own = e.path is not None and Path(e.path).resolve() == Path(devices[0]).resolve()
            (device_check if own else c).problems.append(
                Problem(e.path or str(f), e.detail if own else f"against {devices[0]}: {e.detail}", e.line, e.key))
            continue
        for pf in fit.flagged:
            if pf.swapped is not None:                     # certain: `rodlab fixture` writes nothing from it
                a, b = pf.swapped
                line = next((int(ln) for j, n, ln in zip(probes.position, probes.feature, probes.lines)
                             if int(j) == pf.position and n == a), None)
                c.problems.append(Problem(str(f), f"position {pf.position} against {devices[0]}: features {a!r} and "
                                          f"{b!r} are swapped (exchanged, the position fits within the accuracy)",
                                          line, "feature", f"exchange {a!r} and {b!r} at position {pf.position}"))
                continue
            c.warnings.append(f"position {pf.position} against {devices[0]}: feature {pf.suspect[0]!r} lies "
                              f"{pf.suspect[1] * 1e3:.0f} um off the fit of the others (chi-square {pf.chi2:.1f} over "
                              f"{pf.dof}); `rodlab fixture` flags it: probe it again or check the device's seat")


def cmd_validate(args) -> int:
    bad = []
    robot = None
    if args.robot:
        robot = resolve_robot(args.robot)
    checks = []
    for f in args.files:
        check = validate_file(f, args.format)
        if robot is not None and check.ok and check.format in _ROBOT_CHECKED:
            _check_against_robot(check, f, robot)
        checks.append((f, check))
    _check_positions(checks)
    _check_probes(checks)
    for f, check in checks:
        fmt = check.format or "unknown format"
        if check.ok:
            print(f"{f}: {fmt}, valid" + (f" ({check.note})" if check.note else "")
                  + (f", but with {len(check.warnings)} warning(s):" if check.warnings else ""))
            for w in check.warnings:
                print(f"  warning: {w}")
            continue
        bad.append(f)
        print(f"{f}: {fmt}, {len(check.problems)} problem(s)", file=sys.stderr)
        for prob in check.problems:
            print(f"  {prob}", file=sys.stderr)
    if bad:
        print(f"rodlab validate: error: {len(bad)} of {len(args.files)} file(s) not valid: {', '.join(bad)}",
              file=sys.stderr)
        return 2
    return 0
