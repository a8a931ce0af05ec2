"""Package namespaces that load a module on first use of one of its names (PEP 562).

A domain package whose ``__init__`` imports every module makes each command pay for all of them: ``rodlab fea``
on a cached mesh would import the CAD renderer, the frame model the solid FEA. ``lazy_exports`` gives such a
package a module ``__getattr__`` and ``__dir__`` that import the owning module the first time a name is asked for.
"""
from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: Mapping[str, str], namespace: dict) -> tuple[Callable, Callable]:
    """``(__getattr__, __dir__)`` for ``package`` whose public names ``exports`` map to their module (relative to
    the package); a name once loaded is stored in the package's ``namespace`` (its ``globals()``)."""

    def __getattr__(name: str):
        try:
            module = exports[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(f".{module}", package), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(exports))

    return __getattr__, __dir__
