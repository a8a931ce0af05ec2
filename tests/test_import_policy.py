"""Imports sit at the top of the module; an import inside a function body needs one of three reasons (issue 51,
docs/architecture.md, Conventions):

(a) a heavy dependency: an optional extra of pyproject.toml (``[project.optional-dependencies]``), a
    dependency not declared at all (used when installed), or one of the few heavy required ones in
    ``HEAVY_REQUIRED`` (each with its measured import time); or a module of ours that loads one where the
    importing module's users must not pay for it, marked ``# heavy: <what it loads, how long>`` on the line
    (the comment must name one of those dependencies);
(b) the CLI's lazy start-up: ``rodlab --help`` builds the parser from every module of ``rodlab/app/cli`` (each
    ``cmd_*.py`` registers its sub-command), so a handler there imports its domain module when it runs; this
    counts only for a module that ``rodlab --help`` does not load anyway (found by running it);
(c) an import cycle, marked on the import's line with ``# cycle: <why>``.

The scan walks every installed package folder (pyproject's package-dir: the core and the application in
rodlab/, geometry/, fea/, stiffness_rig/, calibrate/) with ``ast``.
"""
import ast
import re
import subprocess
import sys
from functools import lru_cache

import pytest

from source_tree import PACKAGE_DIRS, PYPROJECT, ROOT, package_of

#: distribution name -> the top-level names it installs, where they differ
IMPORT_NAMES = {"pyserial": ("serial",), "import-linter": ("importlinter",), "scikit-fem": ("skfem",),
                "scikit-sparse": ("sksparse",), "vtk": ("vtk", "vtkmodules"), "pillow": ("PIL",)}

#: Heavy dependencies that pyproject requires, each imported where it is needed so that the CLI's start-up and
#: the paths that do not need it stay fast. Cumulative `python -X importtime -c "import X"` on the 2-core
#: development machine, 2026-11-27 (numpy, ~50 ms, included; `rodlab --help` imports ~0.2 s in all and loads
#: numpy but none of these):
HEAVY_REQUIRED = {
    "scipy": "68 ms; scipy.sparse 184 ms, .sparse.linalg 259 ms, .optimize 342 ms, .spatial 338 ms, .stats 655 ms",
    "pandas": "259 ms",
    "matplotlib": "113 ms; matplotlib.pyplot 296 ms",
    "skfem": "208 ms (scikit-fem)",
    "dask": "102 ms; dask.distributed 303 ms (dask[distributed])",
    "distributed": "303 ms",
    "yourdfpy": "407 ms (trimesh, lxml)",
    "pypardiso": "498 ms (MKL); also platform-conditional",
    "jsonschema": "46 ms: a quarter of `rodlab --help`, which loads rodlab.core.schema",
    "tqdm": "28 ms: 14 % of `rodlab --help`, which loads rodlab.core.progress (only long runs draw a bar)",
}

CYCLE = re.compile(r"#\s*cycle:\s*\S")
HEAVY_MARK = re.compile(r"#\s*heavy:(.*)")


def _requirement_names(requirements) -> set[str]:
    names = set()
    for req in requirements:
        m = re.match(r"\s*([A-Za-z0-9_.-]+)\s*(?:\[([^\]]*)\])?", req)
        name, extras = m.group(1).lower(), m.group(2)
        if name == PYPROJECT["project"]["name"]:
            continue
        names.update(IMPORT_NAMES.get(name, (name.replace("-", "_"),)))
        names.update(e.strip() for e in (extras or "").split(",") if e.strip())  # dask[distributed] -> distributed
    return names


def heavy_names() -> set[str]:
    """Top-level import names that reason (a) covers."""
    optional = PYPROJECT["project"]["optional-dependencies"].values()
    return _requirement_names(r for reqs in optional for r in reqs) | set(HEAVY_REQUIRED)


def _is_declared_or_local(top: str) -> bool:
    declared = _requirement_names(PYPROJECT["project"]["dependencies"]) | heavy_names()
    return top in declared or top == "rodlab" or top in sys.stdlib_module_names


def _imported_modules(node, package: str | None) -> list[str]:
    """The absolute module names an import statement loads (``from X import y``: X)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    if node.level == 0:
        return [node.module]
    parts = (package or "").split(".")
    base = parts[: len(parts) - node.level + 1]
    return [".".join(base + ([node.module] if node.module else []))]


def function_imports(text: str):
    """(line, end line, import node) for each import inside a function body (nested functions included)."""
    found = []

    def visit(node, in_function: bool):
        for child in ast.iter_child_nodes(node):
            if in_function and isinstance(child, (ast.Import, ast.ImportFrom)):
                found.append(child)
            visit(child, in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)))

    visit(ast.parse(text), False)
    return found


def classify(node, lines: list[str], where: str, package: str | None, startup: frozenset[str]) -> str | None:
    """The reason an import inside a function is allowed (``"heavy"``, ``"cli"``, ``"cycle"``), or None."""
    span = "\n".join(lines[node.lineno - 1: node.end_lineno])
    if CYCLE.search(span):
        return "cycle"
    marks = HEAVY_MARK.findall(span)
    if marks and heavy_names() & set(re.findall(r"[A-Za-z_][A-Za-z0-9_]*", " ".join(marks))):
        return "heavy"
    modules = _imported_modules(node, package)
    tops = {m.split(".")[0] for m in modules}
    if tops <= heavy_names() or not all(_is_declared_or_local(t) for t in tops):
        return "heavy"
    if where.startswith("rodlab/app/cli/") and not all(m in startup for m in modules):
        return "cli"
    return None


@lru_cache(maxsize=1)
def startup_modules() -> frozenset[str]:
    """The modules ``rodlab --help`` loads (a fresh interpreter)."""
    code = ("import sys\nfrom rodlab.app.cli.main import build_parser\nbuild_parser()\n"
            "print('\\n'.join(sorted(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=ROOT)
    return frozenset(out.stdout.split())


def _python_files():
    for folder in sorted({ROOT / d for d in PACKAGE_DIRS.values()}):
        for path in sorted(folder.rglob("*.py")):
            if not {".venv", "build", "tests"} & set(path.relative_to(ROOT).parts):
                yield path


def scan(startup: frozenset[str]):
    """{file: [(line, source, reason or None), ...]} for every import inside a function."""
    result = {}
    for path in _python_files():
        where = path.relative_to(ROOT).as_posix()
        text = path.read_text(encoding="utf-8")
        lines = text.splitlines()
        hits = [(n.lineno, lines[n.lineno - 1].strip(), classify(n, lines, where, package_of(path), startup))
                for n in function_imports(text)]
        if hits:
            result[where] = hits
    return result


def test_the_scan_classifies_each_reason():
    """The checker must be able to fail: a light import inside a function is reported, each of the three
    reasons is recognised, and module-level imports (also under ``if``/``try``) are not looked at."""
    text = ("import numpy as np\ntry:\n    import tomllib\nexcept ImportError:\n    tomllib = None\n"
            "def f():\n    import gmsh\n    import matplotlib.pyplot as plt\n    from scipy.optimize import least_squares\n"
            "    from .rod import Rod\n    from .report import (Source,  # cycle: report imports this module\n"
            "                         classify)\n    import json\n    def g():\n        from rodlab.fea import run_solid\n"
            "    from .plots import draw  # heavy: loads matplotlib.pyplot (0.3 s)\n"
            "    from .rod import rows  # heavy: a big module\n")
    lines = text.splitlines()
    startup = frozenset({"rodlab", "rodlab.app.cli", "rodlab.app.cli.rod", "json"})
    got = [(n.lineno, classify(n, lines, "rodlab/app/cli/x.py", "rodlab.app.cli", startup))
           for n in function_imports(text)]
    assert got == [(7, "heavy"), (8, "heavy"), (9, "heavy"), (10, None), (11, "cycle"), (13, None), (15, "cli"),
                   (16, "heavy"), (17, None)]       # a `# heavy:` mark must name a heavy dependency
    # outside the CLI a domain import in a function has no reason
    node = function_imports(text)[6]
    assert classify(node, lines, "rodlab/app/pipeline.py", "rodlab.app", startup) is None


def test_heavy_names_come_from_pyproject():
    names = heavy_names()
    assert {"build123d", "gmsh", "pyvista", "vtk", "vtkmodules", "meshio", "dask", "distributed"} <= names
    assert {"numpy", "filelock", "serial", "minimalmodbus"}.isdisjoint(names)


@pytest.fixture(scope="module")
def imports_in_functions():
    return scan(startup_modules())


def test_imports_are_at_the_top_unless_there_is_a_reason(imports_in_functions):
    bad = [f"{where}:{line}: {src}" for where, hits in sorted(imports_in_functions.items())
           for line, src, reason in hits if reason is None]
    assert not bad, ("imports inside functions without a reason; move each to the top of its module, or mark an "
                     "import cycle with `# cycle: <why>` on its line (heavy dependencies and the CLI's lazy "
                     "start-up are recognised by themselves; see this test's docstring):\n" + "\n".join(bad))
