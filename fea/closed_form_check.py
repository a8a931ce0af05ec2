"""Whether the closed form (paper Eqs. 15-18, ``rodlab compliance`` / ``info``) can be trusted on a design: it
models the tubes and the bend as beams, without the bend's ovalisation or the sleeves' shear lag, and is 3-25 %
too stiff on the built-in rods (docs/fea.md). On a thin-walled tube with a wide bend it can be far stiffer: a
new-user trial's aluminium 100 x 1 mm rod had a closed-form c_rod of 163 um against the solid FEA's 583 um, with
nothing said. :func:`closed_form_notes` compares it with the beam frame (which has both) and names the frame's
own range notes (:func:`~fea.frame.frame_range_notes`).
"""
from __future__ import annotations

import numpy as np

from rodlab.core.compliance import RodCompliance
from rodlab.core.design import RodDesign

from .frame import frame_compliance, frame_range_notes

__all__ = ["closed_form_notes", "CLOSED_FORM_SPREAD"]

#: the closed form's largest C_F entry may lie this far below the frame's before it is noted (its stated spread
#: against the solid FEA is 3-25 %)
CLOSED_FORM_SPREAD = 0.30


def closed_form_notes(design: RodDesign, calc: RodCompliance) -> list[str]:
    """What a user of ``calc`` (the closed form of ``design``) must know: the frame's largest C_F entry more than
    :data:`CLOSED_FORM_SPREAD` above it, and where the design lies outside the frame's calibrated range (then
    only the solid FEA settles it). Empty when neither."""
    CF_frame, _ = frame_compliance(design)
    k = int(np.argmax(np.abs(np.diag(CF_frame))))
    ratio = float(CF_frame[k, k] / calc.C_F[k, k]) if calc.C_F[k, k] > 0 else float("nan")
    outside = frame_range_notes(design)
    notes = []
    if np.isfinite(ratio) and abs(ratio - 1.0) > CLOSED_FORM_SPREAD:
        notes.append(f"the beam frame, which has the bend's ovalisation and the sleeves' shear lag, gives "
                     f"c{k + 1}{k + 1} {ratio:.2f} x the closed form's on this design (the closed form's spread is "
                     f"3-25 %): use `rodlab fea --model solid` (or the frame) for its compliance file")
    if outside:
        notes.append("outside where rodlab's models were checked against the solid FEA (" + "; ".join(outside) +
                     "): check this design with `rodlab fea --model solid`")
    return notes
