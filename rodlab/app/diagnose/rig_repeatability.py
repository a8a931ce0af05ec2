"""Is what the model leaves in the hold means the rig's repeatability, or structure?

Where a recording's hold means scatter from one repeat of a hold to the next beyond their reading noise
(:func:`.rig_noise.repeat_scatter`), that scatter is the rig's repeatability (re-seating of the hanger, friction
from hold to hold) only when nothing returns at every repeat. Each hold mean is modelled as its group's shared
misfit plus ``tau^2 + sigma^2 / n`` of scatter (``tau`` the hold-to-hold scatter [mm], estimated robustly from
the groups; ``n`` the hold's readings), groups being the holds that repeat one (gauge, load axis and sign, mass,
branch). The scatter is taken for repeatability only when every test below passes, so that the burden of proof
lies on the scatter, not on a real effect (a review: a load hysteresis with 2 repeats and a 2.5 um stray hold
had been called repeatability at p = 0.007 and 0.004):

- the holds repeat at least :data:`MIN_REPEATS` times (the median group; with 2 a shared misfit is barely
  testable);
- the groups' shared means together: chi-square p >= :data:`P_OMNIBUS`, the degrees of freedom reduced by the
  parameters fitted to the hold means (a shared misfit is partly absorbed by them);
- the largest group's shared mean alone, Bonferroni over the groups: p >= :data:`P_WORST`;
- no hold off its group by more than :data:`STRAY_Z` of its scatter (a stray hold is the stray-hold path's).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rodlab.stiffness_rig.samples import RigSamples

from .chi2 import chi2_sf
from .rig_noise import CHI2_1_MEDIAN, repeated_hold_means

__all__ = ["Repeatability", "repeatability", "MIN_REPEATS", "P_OMNIBUS", "P_WORST", "STRAY_Z"]

#: the median group of repeated holds must have at least this many repeats
MIN_REPEATS = 3
#: the shared means' chi-square must be at least this likely under scatter alone ...
P_OMNIBUS = 0.05
#: ... and the largest one's (Bonferroni over the groups) at least this
P_WORST = 0.01
#: a hold this many of its scatter SDs off its group's other holds is a stray hold, not repeatability
STRAY_Z = 5.0


@dataclass(frozen=True)
class Repeatability:
    """The hold-to-hold scatter of a model's residual and the tests that it is nothing else.

    tau_mm : hold-to-hold scatter beyond the readings' noise [mm]; hold_sd_mm : the scatter of one hold's mean,
    reading noise included, for the median hold [mm]; x_noise : hold_sd_mm over the noise of a hold's mean [-];
    repeats : the median group's repeats; p_omnibus, p_worst : the shared-misfit tests' p-values; worst_hold_z :
    the largest hold's distance from its group in scatter SDs [-]
    """

    tau_mm: float
    hold_sd_mm: float
    x_noise: float
    repeats: int
    p_omnibus: float
    p_worst: float
    worst_hold_z: float

    @property
    def scatter_only(self) -> bool:
        """Whether the residual hold means are the rig's repeatability and nothing else (every test passes)."""
        return (self.repeats >= MIN_REPEATS and self.p_omnibus >= P_OMNIBUS and self.p_worst >= P_WORST
                and self.worst_hold_z <= STRAY_Z)

    def to_dict(self) -> dict:
        return {"repeatability_mm": self.hold_sd_mm, "hold_scatter_tau_mm": self.tau_mm,
                "repeat_scatter_x_noise": self.x_noise, "repeats": self.repeats,
                "shared_misfit_p": self.p_omnibus, "worst_group_p": self.p_worst, "worst_hold_z": self.worst_hold_z}


def repeatability(data: RigSamples, resid: np.ndarray, sigma: float, n_fitted: int) -> Repeatability | None:
    """The hold-to-hold scatter of ``resid`` (a model's residual of each reading [mm]) with ``sigma`` [mm] the noise
    of one reading and ``n_fitted`` the parameters fitted to the hold means (effects, linear entries); None when
    no hold repeats."""
    groups = repeated_hold_means(data, resid)
    if not groups:
        return None
    tau2 = _tau2(groups, sigma)
    z_shared, z_stray = [], [0.0]
    for means, counts in groups:
        var = tau2 + sigma ** 2 / counts                                 # each hold mean's scatter [mm^2]
        k = means.size
        z_shared.append(float(means.mean()) / math.sqrt(float(var.sum()) / k ** 2))
        z_stray += list(np.abs(means - means.mean()) / np.sqrt(var * (k - 1) / k))
    z = np.array(z_shared)
    dof = max(z.size - n_fitted, 1)
    worst = float(np.abs(z).max())
    p_one = math.erfc(worst / math.sqrt(2.0))
    n_med = float(np.median(np.concatenate([c for _, c in groups])))
    hold_sd = math.sqrt(tau2 + sigma ** 2 / n_med)
    return Repeatability(math.sqrt(tau2), hold_sd, hold_sd / (sigma / math.sqrt(n_med)),
                         int(np.median([m.size for m, _ in groups])), chi2_sf(float(z @ z), dof),
                         min(1.0, p_one * z.size), float(max(z_stray)))


def _tau2(groups: list, sigma: float) -> float:
    """The hold-to-hold variance beyond the readings' noise [mm^2]: the median over the holds of the squared
    deviation from their group's mean (corrected for the mean's own share), over chi-square(1)'s median, less the
    median hold's reading noise; 0 at least."""
    d2 = []
    for means, _ in groups:
        k = means.size
        d2 += list((means - means.mean()) ** 2 * k / (k - 1))
    n_med = float(np.median(np.concatenate([c for _, c in groups])))
    return max(float(np.median(d2)) / CHI2_1_MEDIAN - sigma ** 2 / n_med, 0.0)
