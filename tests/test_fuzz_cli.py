"""Property-based fuzzing of the CLI itself: every sub-command with generated arguments and files.

For each sub-command the arguments come from its own argparse definition: input files from a pool (valid,
corrupted, empty, binary, a folder, missing, the wrong kind), outputs into a fresh folder (sometimes under a
regular file), option values from a token pool (negative, zero, NaN, inf, huge, text, lists, ranges) and
invalid choices. Each run must end with an exit code (0, 1, 2 or 3), never a traceback; exit 2 prints one
error line naming the argument, file or key at fault; a failed run leaves no output file behind.

Folders named like the built-ins (``tx90/``, ``ur5/``, ``rod1/``) sit in every run's working folder: a built-in
name must still mean the built-in. Broken URDFs (a misspelled link, a joint cut out of the chain, a vector
without three numbers) must be refused naming the URDF and its line, by every command that takes a robot.

Long jobs (demo, study, sweep, cad, mesh, solid fea, report, acquisition, the simulator) always get a broken
main input, so they are fuzzed on their argument and file checks, not run for minutes.

``RODLAB_FUZZ_EXAMPLES=N`` runs N examples per sub-command (default 6); with ``RODLAB_FUZZ_STATS=FILE`` each
sub-command appends its exit-code counts (JSON lines) to FILE. docs/reliability.md records a long run.
"""
from __future__ import annotations

import argparse
import collections
import contextlib
import io
import json
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "examples"
EXAMPLES = int(os.environ.get("RODLAB_FUZZ_EXAMPLES", "6"))

TOKENS = ["nan", "inf", "-inf", "-1", "-3", "0", "1e308", "abc", "", "0.5", "2", "10", "1,2", "-1,2", "0.5,1.0",
          "y,z,x", "q", "300:100:50", "150:300:50", "1:2:0", "x=1", "base_x=0.1", "tx90", "TX90", "r2000", "rod1",
          "1#", "friction:F_f_N=0.3", "creep:phi=x", "nope:a=1", "joint:1", "a" * 300, "\u00e9\u00e8", "--"]
FILE_KEYS = {"design", "recording", "sim", "rod", "campaign", "fixture", "validate", "points", "profile", "plan",
             "base", "joints", "robot", "run_dir", "rod_true", "designs", "rig", "files", "calibration", "urdf",
             "fields_file", "device", "probe"}
OUT_KEYS = {"output", "json", "png", "export", "joints_out", "cache", "link", "fields"}
#: sub-commands whose valid runs take minutes or need hardware: always fuzzed with a broken main input
HEAVY = {"demo": None, "report": "run_dir", "cad": "design", "mesh": "design", "sweep": "base", "study": "designs",
         "rig acquire": "profile", "rig simulator": "sim", "fea": "design"}


def _device_file(folder: Path) -> Path:
    from rodlab.calibrate.device import ideal_device, write_device
    return write_device(ideal_device(), folder / "multical.device.json")


def _probe_file(folder: Path) -> Path:
    import numpy as np

    from rodlab.calibrate.device import ideal_device
    from rodlab.calibrate.probe import simulated_probe_text
    from rodlab.calibrate.simulate import standard_fixture
    Ts = {j: standard_fixture().transform(j) for j in standard_fixture().poses}
    path = folder / "multical.probe.csv"
    path.write_text(simulated_probe_text(Ts, ideal_device(), 0.005, np.random.default_rng(0)))
    return path


def _pool(folder: Path) -> dict[str, list[Path]]:
    """Input files: per kind the valid one and its corruptions; plus kind-less broken ones."""
    from rodlab.core.calc import calc_rod_compliance
    from rodlab.core.compliance import write_compliance
    from rodlab.core.design_io import builtin_designs, resolve_design
    valid = {"design": builtin_designs()["rod1"],
             "compliance": write_compliance(calc_rod_compliance(resolve_design("rod1")), folder / "rod1.compliance.json"),
             "robot": ROOT / "calibrate" / "robots" / "tx90.toml",
             "profile": ROOT / "stiffness_rig" / "plans" / "simulator.profile.toml",
             "plan": ROOT / "stiffness_rig" / "plans" / "quick.plan.toml",
             "device": _device_file(folder), "probe": _probe_file(folder)}
    if SHARED.is_dir():
        valid["recording"] = shutil.copy(SHARED / "rig-null.rig.csv", folder / "rig-null.rig.csv")
        for name in ("campaign", "fixture", "validation"):
            src = next((SHARED / "campaign-null").glob(f"multical.{name}.*"))
            valid[name] = shutil.copy(src, folder / src.name)
    pool: dict[str, list[Path]] = {}
    for kind, path in valid.items():
        data = Path(path).read_bytes()
        cut = folder / f"cut-{kind}{''.join(Path(path).suffixes)}"
        cut.write_bytes(data[: len(data) // 3])
        swapped = folder / f"swap-{kind}{''.join(Path(path).suffixes)}"
        swapped.write_bytes(data.replace(b"0", b"nan", 3).replace(b"1", b"-1", 2))
        pool[kind] = [Path(path), cut, swapped]
    (folder / "empty.csv").write_bytes(b"")
    (folder / "junk.json").write_bytes(bytes(range(256)) * 4)
    (folder / "adir").mkdir(exist_ok=True)
    pool["broken"] = [folder / "empty.csv", folder / "junk.json", folder / "adir", folder / "missing.toml"]
    return pool


POOL_DIR = Path(tempfile.mkdtemp(prefix="rodlab-fuzz-"))
POOL = _pool(POOL_DIR)
ALL_FILES = [p for files in POOL.values() for p in files]


def _commands():
    from rodlab.app.cli.main import build_parser
    out = {}

    def walk(parser, prefix):
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if subs:
            for name, sp in subs[0].choices.items():
                walk(sp, prefix + [name])
            return
        out[" ".join(prefix)] = [a for a in parser._actions if not isinstance(a, argparse._HelpAction)
                                 and a.dest not in ("verbose", "quiet", "debug")]
    walk(build_parser(), [])
    return out


COMMANDS = _commands()


#: the kind of file an argument expects (for near-valid command lines)
KIND = {"design": "design", "base": "design", "designs": "design", "sim": "compliance", "rod": "compliance",
        "rod_true": "compliance", "recording": "recording", "rig": "recording", "campaign": "campaign",
        "fixture": "fixture", "validate": "validation", "points": "validation", "profile": "profile", "plan": "plan",
        "robot": "robot", "device": "device", "probe": "probe"}
SANE = {"int": ["1", "2", "3", "5"], "float": ["0.5", "1.0", "3.0", "8.0"]}


@st.composite
def _value(draw, action, out_dir: Path, broken: bool, sane: bool):
    key = action.dest
    if key in FILE_KEYS:
        if broken:
            return str(draw(st.sampled_from(POOL["broken"])))
        if sane and KIND.get(key) in POOL and draw(st.integers(0, 4)):
            return str(POOL[KIND[key]][0])
        return str(draw(st.sampled_from(ALL_FILES + [Path("rod1"), Path("tx90")])))
    if sane and action.type in (int, float) and draw(st.integers(0, 4)):
        return draw(st.sampled_from(SANE[action.type.__name__]))
    if key in OUT_KEYS:
        name = draw(st.sampled_from(["out.json", "out.csv", "figs", "o.rig.csv", "o.compliance.json", "sub/o.json",
                                     "blocker/o.json"]))
        return str(out_dir / name)
    if action.choices:
        return str(draw(st.sampled_from([*map(str, action.choices)] + ([] if sane else ["bogus"]))))
    return draw(st.sampled_from(TOKENS))


@st.composite
def _argv(draw, command: str, out_dir: Path):
    argv = command.split()
    sane = draw(st.booleans())                        # near-valid command lines reach the computations
    heavy_key = HEAVY.get(command, "")
    for action in COMMANDS[command]:
        broken = heavy_key is not None and action.dest == heavy_key
        wanted = draw(st.integers(0, 4)) > 0 if sane and action.dest in KIND else draw(st.booleans())
        if not (action.required or broken or wanted):
            continue
        if action.nargs == 0:
            argv.append(action.option_strings[0])
            continue
        count = 2 if action.nargs == "+" and draw(st.booleans()) else 1
        values = [draw(_value(action, out_dir, broken, sane)) for _ in range(count)]
        if action.option_strings:
            for v in values:
                argv += [action.option_strings[-1], v]
        else:
            argv += values
    if command == "fea" and "--model" not in argv:
        argv += ["--model", "calc"]
    if heavy_key is None:                             # demo: a bad seed or an output under a regular file
        argv += draw(st.sampled_from([["--seed", "abc"], ["-o", str(out_dir / "blocker" / "run")]]))
    return argv


def _run(argv: list[str], cwd: Path) -> tuple[int, str, bool]:
    """(exit code, stderr, whether argparse refused the arguments), run in ``cwd`` (where default outputs go)."""
    from rodlab.app.cli import main
    err, out = io.StringIO(), io.StringIO()
    here = os.getcwd()
    os.chdir(cwd)
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            try:
                return main(argv), err.getvalue(), False
            except SystemExit as e:                     # argparse: usage line + "error: argument ..."
                return int(e.code or 0), err.getvalue(), True
    finally:
        os.chdir(here)


def _names_the_place(message: str, argv: list[str], command: str) -> bool:
    """The error names a file of the command line, one of the command's options, a key, a line or argparse's
    argument."""
    options = [o for a in COMMANDS[command] for o in a.option_strings]
    tokens = [t for t in argv if t.startswith("-") or os.sep in t or t in ("rod1", "tx90")] + options
    names = [n for t in argv if os.sep in t for n in (Path(t).name, str(Path(t).parent))]
    return ("key `" in message or "argument " in message or "arguments are required: " in message
            or any(t and t in message for t in tokens + names)
            or "line " in message)


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_cli_fuzz(command, tmp_path_factory):
    counts = collections.Counter()

    @settings(max_examples=EXAMPLES, deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(data=st.data())
    def run(data):
        out_dir = tmp_path_factory.mktemp("fuzz")
        (out_dir / "blocker").write_text("a regular file where a folder is expected\n")
        for name in ("tx90", "ur5", "rod1"):           # folders named like built-ins (left by `--json ur5/cal.json`)
            (out_dir / name).mkdir()
        before = {p for p in out_dir.rglob("*")}
        argv = data.draw(_argv(command, out_dir))
        code, err, by_argparse = _run(argv, out_dir)
        counts["argparse" if by_argparse else str(code)] += 1
        assert "Traceback" not in err, (argv, err)
        assert code in (0, 1, 2, 3), (argv, code, err)
        if code == 2:
            lines = [ln for ln in err.strip().splitlines() if "error" in ln]
            assert lines, (argv, err)
            assert _names_the_place(lines[-1], argv, command), (argv, lines[-1])
            if not by_argparse:
                assert lines[-1].startswith(f"rodlab {command}: error:"), (argv, err)   # the subcommand named
        if code not in (0, 3):
            created = {p for p in out_dir.rglob("*")} - before
            assert not created, (argv, code, err, sorted(map(str, created)))
    run()
    if os.environ.get("RODLAB_FUZZ_STATS"):
        with open(os.environ["RODLAB_FUZZ_STATS"], "a") as fh:
            fh.write(json.dumps({"command": command, **counts}) + "\n")


# --- broken URDFs and built-in names shadowed by folders -------------------------------------------------------

UR5 = ROOT / "calibrate" / "robots" / "ur5.urdf"
UR5_POINTS = ROOT / "benchmarks" / "data" / "jacobi2025" / "ur5_random.validation.csv"


@st.composite
def _broken_urdf(draw) -> tuple[str, str]:
    """(a UR5 URDF with one fault, what the fault is)."""
    import re
    text = UR5.read_text()
    kind = draw(st.sampled_from(["link", "cut", "vector"]))
    if kind == "link":                                 # a parent / child naming a link the file does not have
        refs = list(re.finditer(r'<(parent|child) link="([^"]+)"', text))
        m = draw(st.sampled_from(refs))
        links = set(re.findall(r'<link name="([^"]+)"', text))
        name = m.group(2)
        typo = draw(st.sampled_from([t for t in (name[:-1], name + "_", name.replace("_", "", 1), name.upper())
                                     if t and t not in links]))
        return text[:m.start(2)] + typo + text[m.end(2):], kind
    if kind == "cut":                                  # a joint removed: the chain stops before the tip
        joints = list(re.finditer(r'<joint name="[^"]+".*?</joint>', text, flags=re.S))
        m = draw(st.sampled_from(joints))
        return text[:m.start()] + text[m.end():], kind
    vectors = list(re.finditer(r'(xyz|rpy)="([^"]*)"', text))    # two numbers, four, or a word
    m = draw(st.sampled_from(vectors))
    words = m.group(2).split()
    bad = draw(st.sampled_from([" ".join(words[:2]), " ".join(words + ["0"]), " ".join(words[:2] + ["x"]), ""]))
    return text[:m.start(2)] + bad + text[m.end(2):], kind


def test_cli_fuzz_broken_urdfs(tmp_path_factory):
    """calibrate / diagnose / export on a URDF with one fault: exit 2, the URDF and a line named, no output."""
    cal = tmp_path_factory.mktemp("cal") / "cal.json"
    assert _run(["calibrate", "--points", str(UR5_POINTS), "--robot", "ur5", "--fix-unidentifiable", "--json",
                 str(cal)], cal.parent)[0] in (0, 3)

    @settings(max_examples=max(EXAMPLES, 8), deadline=None, derandomize=True,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(data=st.data())
    def run(data):
        out_dir = tmp_path_factory.mktemp("urdf")
        text, kind = data.draw(_broken_urdf())
        urdf = out_dir / "arm.urdf"
        urdf.write_text(text)
        argv = data.draw(st.sampled_from([
            ["calibrate", "--points", str(UR5_POINTS), "--robot", str(urdf), "--json", str(out_dir / "o.json")],
            ["diagnose", "--points", str(UR5_POINTS), "--robot", str(urdf)],
            ["export", str(cal), "--urdf", str(urdf), "-o", str(out_dir / "o.urdf")]]))
        before = set(out_dir.rglob("*"))
        code, err, _ = _run(argv, out_dir)
        assert "Traceback" not in err and code == 2, (kind, argv, err)
        last = err.strip().splitlines()[-1]
        assert last.startswith(f"rodlab {argv[0]}: error: {urdf}, line "), (kind, last)
        assert set(out_dir.rglob("*")) == before, (kind, argv)
    run()


@pytest.mark.parametrize("argv", [
    ["info", "rod1"], ["compliance", "rod1", "-o", "rod1/rod1.compliance.json"],
    ["simulate-campaign", "--robot", "tx90", "--rod", str(POOL["compliance"][0]), "-o", "tx90/campaign"],
    ["diagnose", "--points", str(UR5_POINTS), "--robot", "ur5"],
    ["rig", "simulate", "--sim", "rod1", "-o", "rod1/rec.rig.csv"]])
def test_builtin_names_shadowed_by_folders(argv, tmp_path_factory):
    """A folder named like a built-in robot or design never hides it (the folder is not a file)."""
    cwd = tmp_path_factory.getbasetemp() / "shadow"
    for name in ("tx90", "ur5", "rod1"):
        (cwd / name).mkdir(parents=True, exist_ok=True)
    code, err, _ = _run(argv, cwd)
    assert code in (0, 3), (argv, err)
    assert "unknown robot file kind" not in err and "this is a folder" not in err
