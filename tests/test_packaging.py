"""The installed layout: every source folder is a listed package (a wheel built from pyproject.toml would
otherwise lack it), the data files ship, and the domain folders install only inside ``rodlab``."""
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CONF = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]


def _folder(package: str) -> Path:
    """The source folder of a dotted package name under pyproject's package-dir mapping."""
    dirs = CONF["package-dir"]
    best = max((p for p in dirs if package == p or package.startswith(p + ".")), key=len)
    rest = package[len(best):].lstrip(".")
    return ROOT / dirs[best] / Path(*rest.split(".")) if rest else ROOT / dirs[best]


def test_every_python_folder_is_a_listed_package():
    listed = set(CONF["packages"])
    roots = {ROOT / d for d in CONF["package-dir"].values()}
    found = set()
    for root in roots:
        for init in root.rglob("__init__.py"):
            if ".venv" in init.parts or "build" in init.parts:
                continue
            found.add(init.parent)
    listed_folders = {_folder(p) for p in listed}
    missing = sorted(str(f.relative_to(ROOT)) for f in found - listed_folders)
    assert not missing, f"folders with __init__.py missing from [tool.setuptools] packages: {missing}"
    absent = sorted(p for p in listed if not _folder(p).is_dir())
    assert not absent, f"listed packages without a folder: {absent}"


def test_package_data_globs_match_files():
    for package, globs in CONF["package-data"].items():
        folder = _folder(package)
        for g in globs:
            assert list(folder.glob(g)), f"{package}: no file matches {g} in {folder}"


def test_domain_folders_install_inside_rodlab_only():
    assert CONF["package-dir"] == {"rodlab": "rodlab", "rodlab.geometry": "geometry", "rodlab.fea": "fea",
                                   "rodlab.stiffness_rig": "stiffness_rig", "rodlab.calibrate": "calibrate"}
    assert not any(p.split(".")[0] != "rodlab" for p in CONF["packages"])


def test_builtin_data_found_through_the_installed_names():
    from rodlab.calibrate.robot_formats import builtin_robots
    from rodlab.core.design_io import builtin_designs
    assert {"tx90", "r2000ic165f", "ur10", "ur5"} <= set(builtin_robots())
    assert {f"rod{i}" for i in range(1, 7)} <= set(builtin_designs())
