"""gmsh's mesh generation, guarded against its high-order optimizer ending the process.

A curved (order-2) mesh is untangled by gmsh's high-order optimizer (``Mesh.HighOrderOptimize = 1``). When the
optimizer cannot lift a patch's scaled Jacobian to its critical value, it reports an error from inside an OpenMP
region; with gmsh's default ``General.AbortOnError = 2`` that report is a C++ throw, which cannot leave the
region: ``std::terminate`` ends the Python process with no message (found on rod 1# drawn within its tolerances:
a 4.88 mm wall, R 66.3 mm bend, 36.6 mm rings). Generation therefore runs with errors reported, not thrown
(``AbortOnError = 0``), collected from gmsh's logger and classified afterwards: the optimizer giving up leaves
the patch as it was, so the mesh is generated again with the elastic analogy before the optimization
(``HighOrderOptimize = 2``: slower, ~0.9 s instead of ~0.5 s on rod 1#, and only for such designs); any other
error is a :class:`~geometry.errors.GeometryError` naming gmsh's message. Designs the optimizer handles get the
mesh they always got.

With ``on_linear`` an order-2 mesh is made in two steps, the straight mesh first (``Mesh.ElementOrder = 1``), then
``setOrder(2)`` and the high-order optimizer, so that the caller can read the straight tetrahedra in between: the
same mesh, node for node (checked on rods 1#-6#, ``tests/test_mesh_topology.py``), and a solver can plan its
assembly from them while gmsh curves the elements (~0.15-0.3 s on rod 1#).
"""
from __future__ import annotations

import logging

from collections.abc import Callable

from .errors import GeometryError

__all__ = ["generate_mesh", "session_options", "OPTIMIZER_GAVE_UP"]

log = logging.getLogger(__name__)

#: gmsh's messages when the high-order optimizer gives up on a patch (the patch is left as it was)
OPTIMIZER_GAVE_UP = ("Failed to reach critical value", "Failed to reach target", "Optimization failed",
                     "partially failed")


def generate_mesh(order: int, on_linear: Callable[[], None] | None = None) -> int:
    """Generate the 3-D mesh of the current gmsh model with the options set (the caller holds gmsh, between its
    initialize and finalize); returns the ``HighOrderOptimize`` mode the mesh was made with (0 for straight
    elements). ``on_linear``: called once, for an order-2 mesh, when the straight mesh is there and the elements
    are not yet curved (it may read the model's mesh, not change it). Raises :class:`GeometryError` on a gmsh
    error that is not the optimizer giving up."""
    import gmsh

    mode = int(gmsh.option.getNumber("Mesh.HighOrderOptimize"))
    if order == 2 and mode == 1 and on_linear is not None:
        errors = _generate_in_two_steps(on_linear)
    else:
        errors = _generate_reporting_errors()
    if order == 2 and mode == 1 and _gave_up(errors):
        log.info("gmsh's high-order optimizer gave up (%s); meshing again with the elastic analogy first",
                 "; ".join(errors))
        gmsh.model.mesh.clear()
        mode = 2
        gmsh.option.setNumber("Mesh.HighOrderOptimize", mode)
        errors = _generate_reporting_errors()
    if mode == 2 and _gave_up(errors):
        log.warning("gmsh's high-order optimizer gave up also after the elastic analogy (%s); the mesh's quality "
                    "check decides", "; ".join(errors))
    fatal = [e for e in errors if not _gave_up([e])]
    if fatal:
        raise GeometryError(f"gmsh could not mesh the rod: {fatal[0]}")
    return mode


def _generate_in_two_steps(on_linear: Callable[[], None]) -> list[str]:
    """The straight mesh (``generate(3)`` at order 1), ``on_linear()``, then order 2 and the high-order optimizer
    (``HighOrderOptimize = 1``): what ``generate(3)`` at order 2 does in one call. gmsh's error messages of both
    steps; the second is skipped after a fatal one."""
    import gmsh

    gmsh.option.setNumber("Mesh.ElementOrder", 1)
    gmsh.option.setNumber("Mesh.HighOrderOptimize", 0)
    try:
        errors = _reporting_errors(lambda: gmsh.model.mesh.generate(3))
    finally:
        gmsh.option.setNumber("Mesh.ElementOrder", 2)
        gmsh.option.setNumber("Mesh.HighOrderOptimize", 1)
    if errors:
        return errors
    on_linear()
    return _reporting_errors(lambda: (gmsh.model.mesh.setOrder(2), gmsh.model.mesh.optimize("HighOrder")))


def _generate_reporting_errors() -> list[str]:
    """``gmsh.model.mesh.generate(3)`` with errors reported rather than thrown; gmsh's error messages."""
    import gmsh

    return _reporting_errors(lambda: gmsh.model.mesh.generate(3))


def _reporting_errors(step: Callable[[], object]) -> list[str]:
    """Run ``step`` (gmsh calls) with errors reported rather than thrown; gmsh's error messages."""
    import gmsh

    before = gmsh.option.getNumber("General.AbortOnError")
    gmsh.option.setNumber("General.AbortOnError", 0)
    gmsh.logger.start()
    try:
        step()
        return [m.split(":", 1)[-1].strip() for m in gmsh.logger.get() if m.startswith("Error")]
    finally:
        gmsh.logger.stop()
        gmsh.option.setNumber("General.AbortOnError", before)


def _gave_up(errors: list[str]) -> bool:
    return any(s in e for e in errors for s in OPTIMIZER_GAVE_UP)


def session_options() -> None:
    """gmsh's options for one meshing session: quiet, repeatable, the booleans in parallel, msh 4.1."""
    import gmsh

    gmsh.option.setNumber("General.Terminal", 0)
    gmsh.option.setNumber("General.NumThreads", 1)        # parallel 2-D meshing is not repeatable
    gmsh.option.setNumber("Geometry.OCCParallel", 1)      # the fragment in parallel: ~0.125 -> 0.08 s
    gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
