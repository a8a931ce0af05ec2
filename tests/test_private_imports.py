"""No module imports another module's private name: neither ``from X import _name`` nor ``import X`` then
``X._name``. A name shared between modules is public, with a docstring, in the module that owns it (issue 51).
The scan covers every installed package folder (pyproject's package-dir), scripts/ and benchmarks/; tests may
exercise the private helpers of the module they test."""
import ast
from pathlib import Path

from source_tree import PACKAGE_DIRS, ROOT, package_of


def _source_folders() -> list[Path]:
    return sorted({ROOT / d for d in PACKAGE_DIRS.values()} | {ROOT / "scripts", ROOT / "benchmarks"})


def _module_file(dotted: str) -> Path | None:
    """The source file of the module ``dotted`` (``rodlab.calibrate.identify``), or None when it is not one of
    ours or not a module (a function, a class)."""
    best = max((p for p in PACKAGE_DIRS if dotted == p or dotted.startswith(p + ".")), key=len, default=None)
    if best is None:
        return None
    rest = dotted[len(best):].lstrip(".")
    base = ROOT / PACKAGE_DIRS[best] / Path(*rest.split(".")) if rest else ROOT / PACKAGE_DIRS[best]
    for f in (base.with_suffix(".py"), base / "__init__.py"):
        if f.is_file():
            return f
    return None


def _absolute(node: ast.ImportFrom, package: str | None) -> str | None:
    if node.level == 0:
        return node.module
    if package is None:
        return None
    parts = package.split(".")[: len(package.split(".")) - node.level + 1]
    return ".".join(parts + ([node.module] if node.module else []))


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def private_uses(text: str, where: str, package: str | None = None, is_module=_module_file) -> list[str]:
    """``where:line: ...`` for each private name of another module that ``text`` uses: imported by name, or read
    as an attribute of a module it imported (dunder names such as ``__version__`` are public by convention)."""
    tree = ast.parse(text)
    found, modules = [], set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            modules.update(a.asname or a.name.split(".")[0] for a in node.names if is_module(a.name))
        elif isinstance(node, ast.ImportFrom):
            src = _absolute(node, package)
            for alias in node.names:
                if _private(alias.name):
                    found.append(f"{where}:{node.lineno}: from {'.' * node.level}{node.module or ''} import "
                                 f"{alias.name}")
                elif src and is_module(f"{src}.{alias.name}"):
                    modules.add(alias.asname or alias.name)
    for node in ast.walk(tree):
        if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in modules
                and _private(node.attr)):
            found.append(f"{where}:{node.lineno}: {node.value.id}.{node.attr}")
    return found


def _python_files():
    for folder in _source_folders():
        for path in sorted(folder.rglob("*.py")):
            if not {".venv", "build", "tests"} & set(path.relative_to(ROOT).parts):
                yield path


def test_the_scan_sees_private_uses():
    """The checker must be able to fail: private imports at module level and inside a function, and a private
    attribute of an imported module, are found; public and dunder names, and attributes of objects, are not."""
    text = ("from .identify import _select, solve\nfrom rodlab import __version__\n"
            "from rodlab.app.diagnose import campaign as C\nfrom rodlab.calibrate import identify\n"
            "def f(obj):\n    from .run import _priors as p\n    return p, C._context, obj._cache, identify.__doc__\n")
    assert private_uses(text, "x.py", "rodlab.calibrate") == [
        "x.py:1: from .identify import _select", "x.py:6: from .run import _priors", "x.py:7: C._context"]


def test_no_module_uses_another_modules_private_name():
    files = list(_python_files())
    assert len(files) > 100, f"the scan found only {len(files)} source files: are the folders right?"
    bad = [hit for p in files
           for hit in private_uses(p.read_text(encoding="utf-8"), str(p.relative_to(ROOT)), package_of(p))]
    assert not bad, ("modules use another module's private name; make the name public (with a docstring) in the "
                     "module that owns it, or move it:\n" + "\n".join(bad))
