"""rodlab: design, simulate, measure and use long measuring rods for on-site robot calibration (MultiCal).

The layers, bottom up (docs/architecture.md): ``rodlab.core`` holds the shared types (rod design, materials,
compliance files, frames, units); the domain packages ``rodlab.geometry``, ``rodlab.fea``,
``rodlab.stiffness_rig`` and ``rodlab.calibrate`` depend on it, never on each other; the application
``rodlab.app`` (the CLI, the demo, diagnosis, study, reports) sits on top. The core's stable API is re-exported
here.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from pathlib import Path

__version__ = "0.1.0"

from . import core as _core  # noqa: E402
from .core import *  # noqa: E402,F401,F403  (the stable API: rodlab.core.__all__)

__all__ = ["__version__", *_core.__all__]

#: the core modules, which lived at rodlab.NAME before they moved to rodlab.core.NAME
_CORE_MODULES = frozenset(p.stem for p in Path(__file__).parent.joinpath("core").glob("*.py") if p.stem != "__init__")


class _MovedLoader(importlib.abc.Loader):
    """Hands out the module at its new place (one module object under both names)."""

    def __init__(self, target: str) -> None:
        self.target = target

    def create_module(self, spec):
        warnings.warn(f"{spec.name} moved to {self.target}; import it from there (or the stable API from rodlab)",
                      DeprecationWarning, stacklevel=2)
        return importlib.import_module(self.target)

    def exec_module(self, module) -> None:
        pass


class _MovedCore(importlib.abc.MetaPathFinder):
    """``import rodlab.compliance`` (the path before the core moved to ``rodlab.core``) keeps working."""

    def find_spec(self, fullname, path, target=None):
        head, _, name = fullname.rpartition(".")
        if head != "rodlab" or name not in _CORE_MODULES:
            return None
        return importlib.util.spec_from_loader(fullname, _MovedLoader(f"rodlab.core.{name}"))


if not any(isinstance(f, _MovedCore) for f in sys.meta_path):
    sys.meta_path.append(_MovedCore())


def __getattr__(name: str):
    """``rodlab.compliance`` as an attribute (the core module's old place) still reaches ``rodlab.core.compliance``,
    with the same DeprecationWarning as its import."""
    if name in _CORE_MODULES:
        return importlib.import_module(f"rodlab.{name}")
    raise AttributeError(f"module 'rodlab' has no attribute {name!r}")

