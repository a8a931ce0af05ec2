"""The ``rodlab`` process's start-up: NumPy sub-packages no command uses are loaded only when used.

SciPy (1.17) builds its array-API namespace by copying NumPy's: it asks ``hasattr(numpy, name)`` for every name
in ``dir(numpy)``, and NumPy answers that by importing each lazily-loaded sub-package (``numpy.f2py``,
``numpy.testing`` with ``unittest`` and ``importlib.metadata``, ``numpy.ma`` ...): ~45 ms of every command that
imports ``scipy.sparse`` or ``scipy.optimize`` (a tenth of ``rodlab diagnose --rig``). Here those sub-packages
are put in place as :class:`importlib.util.LazyLoader` modules: the copy finds them without loading them, and
the first real use of one loads it in full. Only the console script does this (:func:`rodlab.app.cli.main.console`),
not a program that imports rodlab.
"""
from __future__ import annotations

import importlib.util
import logging
import sys

import numpy

__all__ = ["DEFERRED", "defer_numpy_submodules"]

log = logging.getLogger(__name__)

#: NumPy sub-packages that no rodlab command needs at start-up (each is loaded on its first real use)
DEFERRED = ("numpy.f2py", "numpy.testing", "numpy.ma", "numpy.ctypeslib", "numpy.char", "numpy.rec", "numpy.strings")


def defer_numpy_submodules(names: tuple[str, ...] = DEFERRED) -> list[str]:
    """Put each of ``names`` (sub-packages of NumPy not loaded yet) in place as a lazily loaded module; returns
    the names deferred. A name NumPy does not have, or one already loaded, is left alone."""
    done = []
    for name in names:
        if name in sys.modules:
            continue
        try:
            spec = importlib.util.find_spec(name)
        except (ImportError, ValueError):
            spec = None
        if spec is None or spec.loader is None:
            continue
        spec.loader = importlib.util.LazyLoader(spec.loader)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
        setattr(numpy, name.rpartition(".")[2], module)
        done.append(name)
    log.debug("NumPy sub-packages loaded on first use: %s", ", ".join(done))
    return done
