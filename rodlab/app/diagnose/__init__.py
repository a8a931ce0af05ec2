"""rodlab diagnose: locate the mismatch between simulation and recordings, name the physics left out,
model it and show the fit improve (rig recordings and calibration campaigns).

The names below load their module on first use (PEP 562): ``rodlab diagnose --rig`` does not import the
campaign diagnosis (~0.3 s of its start-up).
"""
from __future__ import annotations

from rodlab.core.lazy import lazy_exports

#: each public name and the module it comes from
_EXPORTS = {
    "diagnose_rig": "rig",
    "diagnose_campaign": "campaign",
    "corrected_compliance": "export",
    "Diagnosis": "report", "Finding": "report",
}

__all__ = list(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
