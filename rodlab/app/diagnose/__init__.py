"""rodlab diagnose: locate the mismatch between simulation and recordings, name the physics left out,
model it and show the fit improve (rig recordings and calibration campaigns)."""
from .campaign import diagnose_campaign
from .export import corrected_compliance
from .report import Diagnosis, Finding
from .rig import diagnose_rig

__all__ = ["diagnose_rig", "diagnose_campaign", "corrected_compliance", "Diagnosis", "Finding"]
