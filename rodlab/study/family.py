"""The joint-calibrated frame of a design family: one solid FEA run calibrates the frame's joints, which then
carry over to every L1 x L2 member (docs/fea.md). Shared by ``rodlab sweep --calibrate`` and ``rodlab study``."""
from __future__ import annotations

import logging

from rodlab.design import RodDesign

__all__ = ["solid_family_calibration", "cad_available"]

log = logging.getLogger(__name__)


def cad_available() -> bool:
    """True when the cad extra (build123d, gmsh) is importable."""
    try:
        import build123d  # noqa: F401
        import gmsh  # noqa: F401
    except ImportError:
        return False
    return True


def solid_family_calibration(base: RodDesign, L1s=(), L2s=()):
    """A :class:`rodlab.fea.joints.JointCalibration` of ``base``'s family from one solid run of its calibration
    member (``base``, or the grid's nearest design whose free tubes are long enough); needs the cad extra."""
    import rodlab.geometry as geometry
    from rodlab.fea import solid_compliance
    from rodlab.fea.family import calibrate_family, calibration_member

    def solve(d):
        return solid_compliance(d, geometry.mesh_rod, error_estimate=False, keep_displacements=True,
                                tip_moments=True)[1]
    member = calibration_member(base, L1s, L2s)
    log.info("joint calibration of %s's family on a solid run of %s", base.name, member.name)
    return calibrate_family(member, solve)
