"""What a campaign's found physics leaves: the ``unexplained`` finding and where its excess lies (at one clamping
position, changing with the campaign's time, or spread evenly: a device noisier than stated would give that;
:mod:`.spread` holds the tests)."""
from __future__ import annotations

import numpy as np

from rodlab.calibrate.trust import gross, implausible_device
from rodlab.core.enums import FindingKind

from .report import Finding
from .spread import column_basis, position_share_test, time_trend_p

__all__ = ["unexplained_finding", "device_noise_null", "time_trend_test"]


def unexplained_finding(sel, camp, final_test) -> Finding:
    """The finding that says what the found physics leaves (``sel``: the finished
    :class:`~.campaign.CampaignSelection`; ``final_test``: its residual test): residuals above the expected scatter,
    at the position where they are least expected, changing with the campaign's time, or spread evenly over the
    positions (no structure: a device noisier than stated would give that: :mod:`.spread`)."""
    final_rms = sel.rms(sel.cols)
    ew = sel.fit(sel.cols)[2]
    e_mm = (sel.L @ ew).reshape(sel.N, 3)
    pos_rms = {int(j): float(np.sqrt(np.mean(e_mm[camp.position == j] ** 2))) for j in np.unique(camp.position)}
    kept = np.ones(sel.N, dtype=bool)
    kept[sel.used_points] = False                  # dropped outliers: their own columns absorb them
    A = np.column_stack([sel.J] + sel.cols)
    device_scale, null_cov = device_noise_null(sel, ew, A)
    share = position_share_test(ew, A, np.asarray(camp.position), kept, null_cov)
    worst, p_even = share.worst, share.p
    p_time = time_trend_test(sel, ew, A, camp) if p_even > 0.01 else 1.0
    even = p_even > 0.01 and p_time > 0.01
    scatter_um = sel.noise_mm * device_scale * 1e3
    noisier = (f"no device is that noisy (about {scatter_um:.1f} um instead of {sel.noise_mm * 1e3:.1f} um): the "
               "files do not describe this campaign" if gross(final_test.birge, final_rms) else
               f"no MultiCal device scatters about {scatter_um:.1f} um (stated {sel.noise_mm * 1e3:.1f} um): the files "
               "may not describe this campaign, or play that no effect models is at work"
               if implausible_device(scatter_um * 1e-3) else
               f"a device noisier than stated (about {scatter_um:.1f} um instead of {sel.noise_mm * 1e3:.1f} um) "
               "would give this" if device_scale > 1.0 + 1e-6 else
               "the device noise as stated cannot give this: the fixture poses may be less certain than stated")
    where = (f"spread evenly over the positions (least expected share at position {worst}, p = {p_even:.2g}): "
             f"no structure; {noisier}" if even else
             f"spread over the positions but changing with the campaign's time (p = {p_time:.2g}): the robot or the "
             "device changed while it was recorded, in a way no effect's form matches" if p_time <= 0.01 else
             f"least expected at position {worst} (p = {p_even:.2g}), with no modelled cause")
    return Finding(FindingKind.UNEXPLAINED, "time" if p_time <= 0.01 else f"position:{worst}",
                   f"residuals {final_rms * 1e3:.1f} um remain {final_test.birge:.2f} times the expected scatter "
                   f"(device {sel.noise_mm * 1e3:.1f} um and fixture poses; {final_test.describe()}), {where}",
                   {"rms_mm": final_rms, "reduced_chi2": final_test.reduced, "birge_ratio": final_test.birge,
                    "spread": "even" if even else "time" if p_time <= 0.01 else "position", "scatter_um": scatter_um},
                   {}, final_rms, final_rms, {"position_rms_mm": pos_rms, "p_even": p_even, "p_time": p_time})


def time_trend_test(sel, ew: np.ndarray, A: np.ndarray, camp) -> float:
    """:func:`.spread.time_trend_p` of the campaign's time column within its clamping positions (1 without one):
    ``ew`` the whitened residual of the fit with whitened columns ``A`` of the selection ``sel``."""
    t = None if camp.time_s is None else np.asarray(camp.time_s, float)
    if t is None or not np.isfinite(t).all() or np.ptp(t) <= 0:
        return 1.0
    T = np.kron(((t - t.mean()) / np.ptp(t))[:, None], np.eye(3))          # (3N, 3): x, y, z of each point
    # the trend within the positions: positions are recorded one after another, so a trend over the whole
    # campaign would also read an offset of each position (a fixture pose less certain than stated) as drift
    pos = np.asarray(camp.position)
    P = np.kron((pos[:, None] == np.unique(pos)[None, :]).astype(float), np.eye(3))
    return time_trend_p(ew, np.column_stack([A, sel.white(P)]), sel.white(T))


def device_noise_null(sel, ew: np.ndarray, A: np.ndarray) -> tuple[float, np.ndarray]:
    """The evenly spread excess "a device noisier than stated" predicts: the factor s (>= 1) on the device
    noise that makes the expected residual sum of squares the observed one (the fixture poses' uncertainty as
    stated), and the covariance of the whitened noise under it (shape=(3N, 3N))."""
    Dw = sel.white(sel.white(sel.cov_device).T)            # L is symmetric: L^-1 C L^-T
    Fw = sel.white(sel.white(sel.cov - sel.cov_device).T)
    Q = column_basis(A)
    M = np.eye(A.shape[0]) - Q @ Q.T
    s2 = (float(ew @ ew) - float(np.sum(M * Fw))) / max(float(np.sum(M * Dw)), 1e-300)
    s2 = max(s2, 1.0)
    return float(np.sqrt(s2)), s2 * Dw + Fw
