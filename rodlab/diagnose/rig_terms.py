"""The hypothesis library of the rig diagnosis: every rig effect's hypotheses
(:mod:`rodlab.stiffness_rig.effects`, one module per effect), built on the flattened recording.

The simulated model of a sample is ``d_c = C_sim[c, a] F`` (F the load along axis a, signed). Every hypothesis
is a design matrix (n_samples x k) whose columns multiply the effect's parameters, with physical bounds.
"""
from __future__ import annotations

import numpy as np

from rodlab.hypothesis import Hypothesis
from rodlab.stiffness_rig.effects import HypothesisContext, rig_hypotheses
from rodlab.stiffness_rig.samples import RigSamples

__all__ = ["rig_library"]


def rig_library(data: RigSamples, C_sim: np.ndarray, places: dict, tool_mm) -> list[Hypothesis]:
    """All candidate hypotheses for ``data``; ``places``: {location: (point in {T}, member axis)} of joints."""
    base = C_sim[data.comp, data.axis] * data.F                       # the simulated displacement
    return rig_hypotheses(data, HypothesisContext(np.asarray(C_sim, float), base, places,
                                                  np.asarray(tool_mm, float)))
