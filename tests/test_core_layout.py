"""The tree shows the layers (#51): the core lives in rodlab/core/, rodlab/ itself holds only the package's entry
points, and a user's import of a core module by its old path (rodlab.compliance) still works, as the same
module, with a DeprecationWarning."""
import importlib
import sys
import warnings
from pathlib import Path

import pytest

import rodlab

ROOT = Path(rodlab.__file__).resolve().parent


def test_rodlab_holds_no_core_module_beside_the_layers():
    assert {p.name for p in ROOT.glob("*.py")} == {"__init__.py", "__main__.py"}
    assert (ROOT / "core" / "compliance.py").is_file() and (ROOT / "app").is_dir()


def test_the_stable_api_is_the_core_s():
    import rodlab.core as core
    assert set(core.__all__) <= set(rodlab.__all__)
    assert all(getattr(rodlab, n) is getattr(core, n) for n in core.__all__)


@pytest.mark.parametrize("name", ["compliance", "design_io", "units"])
def test_an_old_core_path_still_imports_with_a_warning(name):
    sys.modules.pop(f"rodlab.{name}", None)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        old = importlib.import_module(f"rodlab.{name}")
    assert old is importlib.import_module(f"rodlab.core.{name}")
    assert any(issubclass(w.category, DeprecationWarning) and f"rodlab.core.{name}" in str(w.message) for w in caught)


def test_an_old_core_module_as_an_attribute():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        assert rodlab.design_io.load_design is rodlab.core.design_io.load_design
    with pytest.raises(AttributeError):
        rodlab.no_such_thing


def test_an_unknown_name_is_still_an_import_error():
    with pytest.raises(ModuleNotFoundError):
        importlib.import_module("rodlab.no_such_module")
