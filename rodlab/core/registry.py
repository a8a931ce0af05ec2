"""Registries that find their entries: every module of a package is imported, and the classes it defines that
derive from the registry's base and name their ID are the entries, in the order they declare. Nothing else lists
them, so a new entry is its module and its test (docs/architecture.md, "Registries").

Used by the rig effects (:mod:`rodlab.stiffness_rig.effects`), the campaign effects
(:mod:`rodlab.calibrate.effects`), the compensations (:mod:`rodlab.calibrate.compensations`) and the robot file
formats (:mod:`rodlab.calibrate.robot_formats`, whose entries are module-level ``ROBOT_FORMAT`` objects).
"""
from __future__ import annotations

import importlib
import pkgutil
import sys
from types import ModuleType

from .enums import id_enum
from .errors import RodlabError

__all__ = ["package_modules", "package_classes", "in_declared_order", "sorted_by_id", "refill_id_registry"]


def package_modules(package: str, prefix: str = "") -> list[ModuleType]:
    """The modules of ``package`` whose name starts with ``prefix``, imported, found on the package's ``__path__``
    (a folder added to it is looked in too), in the order they are found."""
    path = sys.modules[package].__path__
    return [importlib.import_module(f"{package}.{info.name}") for info in pkgutil.iter_modules(path)
            if info.name.startswith(prefix)]


def package_classes(package: str, base: type, id_attr: str) -> list[type]:
    """The subclasses of ``base`` that the modules of ``package`` define and that set ``id_attr`` themselves,
    found by importing every module on the package's ``__path__`` (a folder added to it is looked in too), in
    the order the modules are found. Classes a module only imports, and intermediate bases that name no ID,
    are left out."""
    return [c for module in package_modules(package) for c in vars(module).values()
            if isinstance(c, type) and issubclass(c, base) and c is not base
            and c.__module__ == module.__name__ and id_attr in vars(c)]


def in_declared_order(classes: list[type], id_attr: str, what: str) -> list[type]:
    """``classes`` sorted by their ``order`` (an int each declares); :class:`RodlabError` naming both modules when
    two share an ID or a place, or naming the module when one declares no ``order``."""
    for c in classes:
        if not isinstance(vars(c).get("order"), int):
            raise RodlabError(f"{what} {getattr(c, id_attr)!s} ({c.__module__}.{c.__qualname__}) declares no "
                              f"`order = N` (an int: its place in the registry); add one")
    _check_unique(classes, lambda c: c.order, "order", what)
    return sorted(sorted_by_id(classes, id_attr, what), key=lambda c: c.order)


def sorted_by_id(classes: list[type], id_attr: str, what: str) -> list[type]:
    """``classes`` sorted by their ID (for a registry whose order means nothing); :class:`RodlabError` naming
    both modules when two share an ID."""
    _check_unique(classes, lambda c: str(getattr(c, id_attr)), "ID", what)
    return sorted(classes, key=lambda c: str(getattr(c, id_attr)))


def _check_unique(classes: list[type], key, name: str, what: str) -> None:
    seen = {}
    for c in classes:
        other = seen.setdefault(key(c), c)
        if other is not c:
            raise RodlabError(f"{what}s {other.__module__} and {c.__module__} both have the {name} {key(c)!r}; "
                              f"give each its own")


def refill_id_registry(package: str, base: type, registry: dict, enum_name: str, doc: str, what: str) -> type:
    """An effect registry found anew: the ``base`` subclasses the modules of ``package`` define with their ID
    (``effect``) and place (``order``), in that order; the Enum ``enum_name`` of their IDs (:func:`id_enum`:
    the same IDs give back the same class); each class's ``effect`` made its member; ``registry`` refilled in
    place (a class already there keeps its instance). Returns the Enum."""
    classes = in_declared_order(package_classes(package, base, "effect"), "effect", what)
    enum = id_enum(enum_name, [str(c.effect) for c in classes], module=package, doc=doc)
    models = {type(m): m for m in registry.values()}
    for c in classes:
        c.effect = enum(str(c.effect))
    registry.clear()
    registry.update({c.effect: models.get(c) or c() for c in classes})
    return enum
