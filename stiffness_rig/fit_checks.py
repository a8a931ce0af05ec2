"""What a load-deflection fit (:mod:`.fit`) checks in its own result before a measured compliance file is
written: the rod's compliance is symmetric (reciprocity: c_mn = c_nm), and the hold averages lie on their lines
to within their noise. Both failed silently before (new-user trial, 2026-11-28): a perpendicular gauge reversed
for one series gave c13 = -1.19 and c31 = +1.20 um/N, averaged to 0.003 in the file; a gauge bumped by 20 um
mid-recording or one mistyped mass moved c22 by 1-5 % with nothing said.
"""
from __future__ import annotations

import numpy as np

from rodlab.core.units import G0

from .errors import NoLoadResponse
from .instrument_profile import UNITS

__all__ = ["check_load_response", "direction_warnings", "inverse_variance_mean", "structural_zero_warnings",
           "reciprocity_problems", "lack_of_fit_warnings",
           "gauge_scale_problems", "load_drift_warnings", "load_scale_problems", "scale_cause", "RECIPROCITY_Z",
           "LACK_FACTOR", "GAUGE_SCALE_RATIO", "LOAD_SCALE_REFUSE"]

_AX = "xyz"
#: two measured entries c_mn, c_nm further apart than this many standard errors break reciprocity ...
RECIPROCITY_Z = 10.0
#: ... when they also differ by this share of the larger one (a tilted load or gauge gives a few per cent)
RECIPROCITY_SHARE = 0.2
#: a pair apart by this many standard errors and this share is warned of (not refused): a gauge tilted 3 deg
#: towards x had broken c13 = c31 by 2.7 % at 6 standard errors, c33 1.3 % low, without a word (an independent
#: recordings trial)
RECIPROCITY_WARN_Z, RECIPROCITY_WARN_SHARE = 5.0, 0.02
#: on-axis entries measured / simulated that differ by more than this factor between gauges: one reads in
#: other units (inches 25.4, um 1000) or through a lever; no rod is that much softer along one axis alone
GAUGE_SCALE_RATIO = 5.0
#: unit slips a gauge column can have, and their factors
UNIT_FACTORS = {"inches and millimetres": 25.4, "micrometres and millimetres": 1000.0,
                "centimetres and millimetres": 10.0}
#: a ratio within this share of a units factor is that slip
UNIT_FACTOR_TOLERANCE = 0.15
#: a load cell whose readings grow with the hung weight this share faster or slower than it (beyond 5 standard
#: errors) reads another unit or through a wrong calibration factor: the fit is refused (a calibrated cell is off by
#: well under 1 %; kgf read as N is 0.102, lbf 0.225) ...
LOAD_SCALE_REFUSE = 0.10
#: ... and from this share on it is warned of (the fit then uses the cell's readings, as it should)
LOAD_SCALE_WARN = 0.02
#: the hold averages of a line scatter about it by more than this many times a hold average's noise
LACK_FACTOR = 5.0


def reciprocity_problems(M: np.ndarray, S: np.ndarray) -> tuple[list[str], list[str]]:
    """(refusals, warnings) from the measured entries ``M`` [mm/N] and their standard errors ``S`` (NaN where not
    measured), shape=(3, 3): a pair of opposite signs, each clearly measured, is a gauge reversed in one series
    (the file would average it away: refused) when they are also alike in size (b = -a within
    :data:`RECIPROCITY_SHARE`: a gauge block turned a little makes an entry whose true value is 0 come out
    +theta c22 and -theta c11, of opposite signs but unlike sizes); a pair that differs otherwise beyond
    :data:`RECIPROCITY_Z` SEs and :data:`RECIPROCITY_SHARE` is warned of."""
    refuse, warn = [], []
    for i in range(3):
        for j in range(i + 1, 3):
            a, b, sa, sb = M[i, j], M[j, i], S[i, j], S[j, i]
            if not (np.isfinite(a) and np.isfinite(b)):
                continue
            z = abs(a - b) / max(np.hypot(sa, sb), 1e-15)
            if z <= RECIPROCITY_WARN_Z or abs(a - b) <= RECIPROCITY_WARN_SHARE * max(abs(a), abs(b)):
                continue
            if z <= RECIPROCITY_Z or abs(a - b) <= RECIPROCITY_SHARE * max(abs(a), abs(b)):
                warn.append(_tilt_warning(M, i, j, z))
                continue
            what = (f"c{i + 1}{j + 1} = {a * 1e3:+.4g} um/N (load {_AX[j]}, {_AX[i]} gauge) but c{j + 1}{i + 1} = "
                    f"{b * 1e3:+.4g} um/N (load {_AX[i]}, {_AX[j]} gauge), {z:.0f} standard errors apart; a rod's "
                    f"compliance is symmetric")
            if a * b < 0 and abs(a) > 5 * sa and abs(b) > 5 * sb and abs(a + b) <= RECIPROCITY_SHARE * abs(a - b):
                refuse.append(f"{what}: opposite signs are a gauge reversed in one series (the {_AX[i]} gauge under "
                              f"the {_AX[j]} load or the {_AX[j]} gauge under the {_AX[i]} load: its sign in the "
                              "profile, or mounted the other way round); averaged, the file would say ~0. Compare "
                              "the signs of those two gauges' readings in the x, y and z series, fix the reversed "
                              "one and fit again")
            else:
                warn.append(f"{what}: a load or gauge off its axis, or a gauge whose gain differs; "
                            "`rodlab diagnose --rig` tells which (the file takes their mean)")
    return refuse, warn


def _tilt_warning(M: np.ndarray, i: int, j: int, z: float) -> str:
    """A reciprocity break of a few per cent: the j gauge tilted towards i by about |c_ij - c_ji| / c_ii (it reads
    that share of the i deflection in the i series), or the i gauge towards j by |c_ij - c_ji| / c_jj; either moves
    the on-axis entries by about that angle times the cross entry."""
    a, b = M[i, j], M[j, i]
    angle = {k: np.degrees(abs(a - b) / abs(M[k, k])) for k in (i, j) if np.isfinite(M[k, k]) and M[k, k] != 0}
    tilt = (f", as the {_AX[j]} gauge tilted ~{angle[i]:.2g} deg towards {_AX[i]} or the {_AX[i]} gauge "
            f"~{angle[j]:.2g} deg towards {_AX[j]} would give" if len(angle) == 2 else "")
    return (f"c{i + 1}{j + 1} = {a * 1e3:+.4g} um/N but c{j + 1}{i + 1} = {b * 1e3:+.4g} um/N, "
            f"{100 * abs(a - b) / max(abs(a), abs(b)):.2g} % and {z:.0f} standard errors apart (a rod's compliance is "
            f"symmetric){tilt}, or a gauge whose gain is off by that share: the on-axis entries may be off by about "
            "that angle (in rad) times the cross entry; `rodlab diagnose --rig` tells which (crosstalk, a gauge's "
            "gain) and its --export corrects for it")


def structural_zero_warnings(M: np.ndarray, S: np.ndarray, C_sim: np.ndarray) -> list[str]:
    """A warning per measured pair where the simulation has a structural zero (a rod symmetric about its plane has
    no c12, c23) but the recording a clear entry (beyond 10 standard errors and 2 % of the pair's smaller diagonal):
    a gauge or a load line tilted, not the rod (an independent recordings trial: a z gauge tilted 2.5 deg towards
    y wrote c23 = 4.4 % of c22 into the file without a word)."""
    out = []
    scale = np.nanmax(np.abs(C_sim))
    for i in range(3):
        for j in range(i + 1, 3):
            if abs(C_sim[i, j]) > 1e-6 * scale:
                continue
            pair = [(v, e) for v, e in ((M[i, j], S[i, j]), (M[j, i], S[j, i])) if np.isfinite(v) and np.isfinite(e)]
            diag = min((abs(M[k, k]) for k in (i, j) if np.isfinite(M[k, k])), default=np.nan)
            if not pair or not np.isfinite(diag):
                continue
            v, e = max(pair, key=lambda p: abs(p[0]) / max(p[1], 1e-15))
            if abs(v) > 10 * e and abs(v) > 0.02 * diag:
                out.append(f"c{i + 1}{j + 1} = {v * 1e3:+.3g} +- {e * 1e3:.1g} um/N where the rod, symmetric about its "
                           f"plane, has none: a gauge or load line tilted by ~{np.degrees(abs(v) / diag):.2g} deg "
                           f"(the on-axis entries off by about that angle times this entry); the file keeps what was "
                           "measured: `rodlab diagnose --rig` fits the tilt (crosstalk) and its --export writes the "
                           "rod's compliance without it")
    return out


#: the lines of one entry loaded in opposite directions differ by more than this many standard errors ...
DIRECTION_Z = 5.0
#: ... and this share of the larger
DIRECTION_SHARE = 0.01


def direction_warnings(lines: list) -> list[str]:
    """A warning per entry whose lines under opposite load directions (``y`` and ``-y``) differ beyond chance
    (:data:`DIRECTION_Z` standard errors and :data:`DIRECTION_SHARE`): a rod softer one way (an instrument trial:
    c22 8 % larger under -y had been written as the mean, with a standard error 5000 x too small)."""
    by_entry: dict = {}
    for ln in lines:
        if ln.component == ln.axis.index:   # an on-axis entry: a cross entry's lines of opposite signs are no softness
            by_entry.setdefault((ln.component, ln.axis.index), {}).setdefault(ln.axis.sign > 0, []).append(ln)
    out = []
    for (c, i), sides in sorted(by_entry.items()):
        if len(sides) < 2:
            continue
        (pos, se_p), (neg, se_n) = (_mean_slope(sides[True]), _mean_slope(sides[False]))
        z = abs(pos - neg) / max(np.hypot(se_p, se_n), 1e-15)
        share = abs(pos - neg) / max(abs(pos), abs(neg), 1e-15)
        if z > DIRECTION_Z and share > DIRECTION_SHARE:
            soft = "-" if abs(neg) > abs(pos) else "+"
            ax = "xyz"[i]
            out.append(f"c{c + 1}{i + 1} is {100 * share:.2g} % larger under a load along {soft}{ax} "
                       f"({1e3 * pos:.4g} um/N along +{ax}, {1e3 * neg:.4g} um/N along -{ax}; {z:.0f} standard errors "
                       "apart): a rod softer one way (a joint or bond that opens one way, a clamp that lifts) or a gauge "
                       "that touches differently; the file holds their mean with their spread in its uncertainty: fit "
                       "one direction's series alone for that direction's compliance")
    return out


def _mean_slope(lines: list) -> tuple[float, float]:
    """The inverse-variance mean of the lines' slopes [mm/N] and its standard error."""
    mean, se, _ = inverse_variance_mean([ln.slope_mm_per_N for ln in lines], [ln.se_mm_per_N for ln in lines])
    return mean, se


def inverse_variance_mean(values, ses) -> tuple[float, float, float]:
    """(the inverse-variance mean of ``values``, its standard error, the chi-square of the values about it)."""
    w = 1.0 / np.maximum(np.asarray(ses, float), 1e-12) ** 2
    v = np.asarray(values, float)
    mean = float(np.sum(w * v) / w.sum())
    return mean, float(1 / np.sqrt(w.sum())), float(np.sum(w * (v - mean) ** 2))


def lack_of_fit_warnings(lines: list, holds, noise_mm: float) -> list[str]:
    """A warning per load axis whose hold averages scatter about its on-axis line by more than
    :data:`LACK_FACTOR` times a hold average's noise (within-hold noise / sqrt(readings per hold))."""
    if not np.isfinite(noise_mm) or noise_mm <= 0:
        return []
    per_hold = noise_mm / np.sqrt(max(float(np.median(holds.n)), 1.0))
    out = []
    for ln in lines:
        if ln.component != ln.axis.index:
            continue
        ratio = ln.residual_rms_mm / per_hold
        if ratio > LACK_FACTOR:
            out.append(f"the holds of load axis {ln.axis.value} scatter {ratio:.0f} times their noise about the line "
                       f"({ln.residual_rms_mm * 1e3:.2f} um rms against {per_hold * 1e3:.2f} um): a gauge that slipped, "
                       "a mass typed wrong, a drift, a hold that had not settled or a stiffness that changes with the load; "
                       "the slope may be biased: run "
                       "`rodlab diagnose --rig` on it (its --export writes the compliance with what it finds removed)")
    return out


def load_drift_warnings(load) -> list[str]:
    """A warning when the load cell's zero drifts (``load``: the fit's :class:`~.load.LoadCheck`, or None)."""
    d = load.drift if load is not None else None
    if d is None or not d.found:
        return []
    return [f"the load cell's zero drifts by {d.span_N:+.3f} N over the recording ({d.rate_N_per_s:+.2e} +- "
            f"{d.se_N_per_s:.1e} N/s, seen in mass x g0 - force_N of the holds with a hanger on, where friction and "
            "tare stay constant): its readings are then not the loads, and the tares and friction printed are off by "
            "up to that much; re-zero the load cell before each series, and run `rodlab diagnose --rig` on the "
            "recording: it tells whether the deflections follow the load cell or the masses"]


def load_scale_problems(load) -> tuple[list[str], list[str]]:
    """(refusals, warnings) when the load cell's readings do not grow as the hung weight on a load axis (``load``:
    the fit's :class:`~.load.LoadCheck`, or None): a unit slip (kgf, lbf read as N) or a wrong calibration factor
    gives a compliance off by that factor with every other check passing (new-user trial, 2026-11-29: kgf as N gave
    r_rod 9.8, written without a word); a cell wired the other way reads -1; one out of an axis's load path 0.
    One refusal for all the axes, its fix said once."""
    causes, warn, fixes = [], [], []
    for sc in (load.scale if load is not None else ()):
        off = abs(sc.ratio - 1.0)
        judged = np.isfinite(sc.se)                   # a short plan's slope is judged on gross slips only
        if not np.isfinite(sc.ratio) or off <= LOAD_SCALE_WARN or (off <= 5 * sc.se if judged else
                                                                   off <= LOAD_SCALE_REFUSE):
            continue
        pm = f" +- {sc.se:.2g}" if judged else " (no scatter left to give its uncertainty)"
        said = (f"on the {sc.axis.value} holds force_N grows {sc.ratio:.4g}{pm} times as fast as mass_kg x "
                f"g0 ({sc.n_holds} holds with a hanger on; a calibrated load cell: 1)")
        if off <= LOAD_SCALE_REFUSE:
            warn.append(f"{said}: its calibration factor is {100 * (sc.ratio - 1):+.1f} % off, or the masses are; the "
                        "fit uses the load cell's readings: check it against a known weight")
            continue
        cause, fix = scale_cause(sc.ratio, sc.axis.value, sc.se if judged else None)
        causes.append(f"{said}: {cause}")
        fixes += [fix] if fix not in fixes else []
    if not causes:
        return [], warn
    return ["; ".join(causes) + f"; {' '.join(fixes)} Or fit this recording on the hung masses alone with "
            "`rig fit --load mass`"], warn


def scale_cause(ratio: float, axis: str, se: float | None = None) -> tuple[str, str]:
    """(what a load-cell scale ``ratio`` far from 1 says, its fix); ``se``: the ratio's standard error where the
    holds give one (a ratio of 0.001 +- 1.5e-6 is a unit, kN read as N or a scale and a unit both converting, not
    a cell out of the load path: an instrument trial had been told 'no load')."""
    if abs(ratio + 1.0) < 0.05:
        return ("the load cell reads with the opposite sign", "Give its channel sign = -1 in the rig profile for "
                "the next recordings; for this one, negate the force_N column.")
    if abs(np.log(max(abs(ratio), 1e-12) / 65536.0)) < np.log(1.05):   # 2^16: a trial's int32 with swapped words
        return ("a 32-bit reading whose two 16-bit Modbus registers are taken in the wrong order (2^16 = 65536)",
                "Set the load-cell instrument's word_order to the other value in the rig profile and record again.")
    miss, unit = min((abs(ratio * factor - 1.0), unit) for unit, factor in UNITS["force"].items() if unit != "N")
    seen = abs(ratio) >= 0.05 or (se is not None and abs(ratio) > 20 * se)   # clearly a response, not noise
    if miss < 0.05 and seen:          # the nearest unit (kgf and daN are 2 % apart; 0.097 is kgf's)
        factor = UNITS["force"][unit]
        twice = (" (or the profile converts twice: a scale and a units both given for it)"
                 if abs(np.log10(factor)) > 2.5 else "")
        return (f"its readings look like {unit}, not N{twice}",
                f"Set the load-cell channel's units = \"{unit}\" in the rig profile for the next recordings; "
                f"for this one, multiply force_N by {factor:.6g}.")
    if abs(ratio) < LOAD_SCALE_REFUSE:
        return (f"it saw no load along {axis} (not in that axis's load path, or not connected)",
                "Check the load cell's place in the load path.")
    return (f"a wrong calibration factor or unit in the rig profile's load-cell channel (the readings x {1 / ratio:.4g} "
            "would be newtons)", "Correct its units or scale and record again.")


def gauge_scale_problems(M: np.ndarray, C_sim: np.ndarray) -> list[str]:
    """A refusal when one gauge's on-axis entry measured / simulated differs from the others' by a units factor
    (:data:`UNIT_FACTORS` within :data:`UNIT_FACTOR_TOLERANCE`, and beyond :data:`GAUGE_SCALE_RATIO`): that gauge
    reads in other units. A ratio that is no units factor is left to the diagnosis: a compliant flange clamp
    raises the small c11 of an L-shaped rod several times more than c22 and c33 (``M``: measured [mm/N], NaN
    where not measured; ``C_sim``: simulated C_F)."""
    r = {i: M[i, i] / C_sim[i, i] for i in range(3) if np.isfinite(M[i, i]) and C_sim[i, i] > 0 and M[i, i] > 0}
    if len(r) < 2 or max(r.values()) / min(r.values()) <= GAUGE_SCALE_RATIO:
        return []
    mid = float(np.exp(np.median(np.log(list(r.values())))))
    odd = max(r, key=lambda i: abs(np.log(r[i] / mid)))
    others = [i for i in r if i != odd]
    ref = float(np.exp(np.mean([np.log(r[i]) for i in others])))
    factor = max(r[odd], ref) / min(r[odd], ref)
    unit = next((name for name, f in UNIT_FACTORS.items() if abs(factor / f - 1.0) <= UNIT_FACTOR_TOLERANCE), None)
    if unit is None:
        return []
    if len(r) == 2:               # two gauges: the one farther from its simulation is the likelier (r_rod 1-2.3)
        odd, ref_i = sorted(r, key=lambda i: abs(np.log(r[i])), reverse=True)
        others, ref = [ref_i], r[ref_i]
    which = (f"the {_AX[odd]} gauge" if len(r) > 2 or abs(np.log(r[others[0]])) < np.log(3.0) else
             f"the {_AX[odd]} or the {_AX[others[0]]} gauge")
    listed = ", ".join(f"r_{i + 1}{i + 1} {r[i]:.3g}" for i in sorted(r))
    return [f"{which} reads {factor:.3g} times {'less' if r[odd] < ref else 'more'} than the "
            f"{'others' if len(r) > 2 else 'other'} against "
            f"the simulation ({listed}): the factor between {unit}; its units or its scale in the profile; fix the "
            "column and fit again"]


def dead_load_warnings(lines: list) -> list[str]:
    """The holds without a hanger lie off the loaded lines as a load missing from ``mass_kg`` whenever the hanger
    is on would put them (a hanger or loading frame not logged, :attr:`~stiffness_rig.fit.LineFit.dead_load_kg`),
    on an on-axis line: the slopes were fitted without those holds, so the file is right; the log is not."""
    kg = np.array([ln.dead_load_kg for ln in lines if ln.component == ln.axis.index and ln.dead_load_kg is not None])
    if not kg.size:
        return []
    low, high = 1e3 * np.median(kg, axis=0)
    size = f"~{low:.0f} g" if high - low < 0.1 * high else f"{low:.0f}-{high:.0f} g (loading / unloading: friction)"
    return [f"the holds without a hanger lie off the loaded lines as a load of {size} "
            f"missing from mass_kg whenever the hanger is on would put them (the hanger or loading frame not counted?): "
            f"the slopes are fitted without those holds, so the compliance is not biased by it; count the hanger in "
            f"mass_kg, or check with `rodlab diagnose --rig` (its tare)"]


def check_load_response(lines: list, rec, holds) -> None:
    """Refuse a recording in which a load axis does not deflect the rod along itself (gauges not connected or
    not touching, no weight hung, a load cell that saw no load): its on-axis slope must be positive and above its
    standard error x 3."""
    for ln in lines:
        if ln.component != ln.axis.index:
            continue
        if ln.slope_mm_per_N > 3 * ln.se_mm_per_N and ln.slope_mm_per_N > 0:
            continue
        backwards = ln.slope_mm_per_N < -10 * ln.se_mm_per_N
        check = _load_cell_cause(holds, ln.axis) or (
            f"the {_AX[ln.component]} gauge reads the rod's motion backwards: give it sign = -1 in the profile "
            f"(or multiply the disp_{_AX[ln.component]}_mm column by -1), or check the load's direction" if backwards
            else "check the gauges (connected, touching the rod, the right channel) and the loading (weights "
                 "hung on that axis)")
        raise NoLoadResponse(f"no load response on axis {ln.axis.value}: the {_AX[ln.component]} gauge moves "
                             f"{ln.slope_mm_per_N * 1e3:.4f} +- {ln.se_mm_per_N * 1e3:.4f} um/N under the load along "
                             f"{ln.axis.value} ({ln.n_holds} holds), nothing a rod does; {check}",
                             path=rec.path, key="load_axis")


def _load_cell_cause(holds, axis) -> str | None:
    """What to check when the load is the load cell's and it is the cause on ``axis``'s holds: it hardly moved while
    the hung weights did (below a tenth of their span: it saw no load), or it fell as they rose (wired or set the
    other way, which reads as gauges reading backwards); else None."""
    if not holds.has_force:
        return None
    on = np.array([a is axis for a in holds.axis])
    w, f = holds.mass_kg[on] * G0, holds.force_N[on]
    span_w = float(np.ptp(w)) if on.any() else 0.0
    span_f = float(np.ptp(f)) if on.any() else 0.0
    if span_w <= 0:
        return None
    if span_f < 0.1 * span_w:
        return (f"the load cell's force_N spans {span_f:.3g} N over these holds while the hung weights span {span_w:.3g} "
                f"N: it saw no load along {axis.value} (not in the load path of that axis, or not connected); check "
                "it, or fit on the hung masses with `rig fit --load mass`")
    if np.corrcoef(w, f)[0, 1] < -0.9:
        return ("the load cell's force_N falls as the hung weight rises: it reads with the opposite sign (the gauges "
                "are not the cause); give its channel sign = -1 in the rig profile, negate this recording's force_N "
                "column, or fit on the hung masses with `rig fit --load mass`")
    if span_f > 10 * span_w or abs(np.corrcoef(w, f)[0, 1]) < 0.5:
        return (f"the load cell's force_N does not follow the hung weights (it spans {span_f:.3g} N over these holds "
                f"where they span {span_w:.3g} N, correlation {np.corrcoef(w, f)[0, 1]:.2f}): its readings are "
                "garbage, not loads (a byte or word order, a scale or a register of the wrong kind in the rig "
                "profile?); check its channel, or fit on the hung masses with `rig fit --load mass`")
    return None
