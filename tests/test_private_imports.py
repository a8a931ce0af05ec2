"""No module imports another module's private name (``from X import _name``): a name shared between modules is
public, with a docstring, in the module that owns it (issue 51). The scan covers every installed package folder
(pyproject's package-dir), scripts/ and benchmarks/; tests may exercise a module's private helpers."""
import ast
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _source_folders() -> list[Path]:
    dirs = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["package-dir"]
    return sorted({ROOT / d for d in dirs.values()} | {ROOT / "scripts", ROOT / "benchmarks"})


def private_imports(text: str, where: str) -> list[str]:
    """``where:line: from X import _name`` for each private name imported from another module in ``text``
    (dunder names such as ``__version__`` are public by convention)."""
    found = []
    for node in ast.walk(ast.parse(text)):
        if not isinstance(node, ast.ImportFrom):
            continue
        for alias in node.names:
            name = alias.name
            if name.startswith("_") and not (name.startswith("__") and name.endswith("__")):
                found.append(f"{where}:{node.lineno}: from {'.' * node.level}{node.module or ''} import {name}")
    return found


def _python_files():
    for folder in _source_folders():
        for path in sorted(folder.rglob("*.py")):
            if not {".venv", "build", "tests"} & set(path.relative_to(ROOT).parts):
                yield path


def test_the_scan_sees_private_imports():
    """The checker must be able to fail: a private import at module level and inside a function is found, a public
    or dunder one is not."""
    text = ("from .identify import _select, solve\nfrom rodlab import __version__\n"
            "def f():\n    from .run import _priors as p\n    return p\n")
    assert private_imports(text, "x.py") == ["x.py:1: from .identify import _select", "x.py:4: from .run import _priors"]


def test_no_module_imports_a_private_name():
    files = list(_python_files())
    assert len(files) > 100, f"the scan found only {len(files)} source files: are the folders right?"
    bad = [hit for p in files for hit in private_imports(p.read_text(encoding="utf-8"), str(p.relative_to(ROOT)))]
    assert not bad, ("modules import another module's private name; make the name public (with a docstring) in the "
                     "module that owns it, or move it:\n" + "\n".join(bad))
