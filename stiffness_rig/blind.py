"""Blind cases for a rig diagnosis, generated from the rig's physical model (never from diagnosis code).

Used by ``benchmarks/diagnose_blind.py`` and the tests to score ``rodlab diagnose --rig`` on recordings it has
never seen; the diagnosis never imports this module (a test checks it).

Each case: a recording on disk plus its truth (effects, locations, parameters, SNR). Effects are sized to
a peak change of the readings of ``snr`` x the per-sample noise, as the contract examples are. Mix: ~30 %
nulls, single effects (SNR 3-60), pairs, other noise levels and protocols, decoys (a bumped hold, a
mislabelled load) and effects outside the library (gauge non-linearity, a step slip, mains hum), for which
the honest answer is ``unexplained``. The mix, noise levels, SNR range, protocols, decoys and outside effects
are defined in ``stiffness_rig/blind_cases.toml`` (:func:`blind_definitions`).
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from rodlab import calc_rod_compliance, resolve_design
from rodlab.core.schema import read_toml_checked

from .effects import joint_places
from .errors import RigError
from .model import Hold, LoadSchedule, RigModel
from .simulate import simulate_recording

__all__ = ["generate_cases", "BlindCase", "blind_definitions", "read_blind_definitions", "FORMAT_BLIND", "unit_effect",
           "peak_change", "scaled_effects", "standard_schedule", "out_of_library"]

FORMAT_BLIND = "rodlab.blind_rig/1"

#: the effects the blind cases draw from (the contract's vocabulary, in its order)
LIBRARY = ["friction", "tare", "creep", "nonlinearity", "crosstalk", "drift", "compliance_scale",
           "torsion_compliance", "joint_compliance"]


@dataclass
class BlindCase:
    """One blind recording (``path``) and its truth (kind, effects with location, parameters and SNR, the
    expected verdict, noise, protocol)."""

    path: Path
    truth: dict


def read_blind_definitions(path) -> dict:
    """Blind-case definitions from ``path`` (``rodlab.blind_rig/1``): {table: {key: value}}; every schema
    problem named at once (file, line, key)."""
    data, _ = read_toml_checked(path, FORMAT_BLIND, RigError)
    return data


@lru_cache(maxsize=None)
def blind_definitions() -> dict:
    """The shipped definitions (``stiffness_rig/blind_cases.toml``)."""
    return read_blind_definitions(Path(str(resources.files("rodlab.stiffness_rig").joinpath("blind_cases.toml"))))


def unit_effect(name, rng, places, variants: bool = False):
    """(effects dict for a unit magnitude, location, scalable keys); ``variants``: other forms of an effect than
    the diagnosis's first hypothesis (a nonlinearity quadratic in the load, or on one load axis only; another gauge
    tilted, or a load line tilted instead of a gauge)."""
    if name == "crosstalk" and variants:
        return _crosstalk_variant(rng)
    if name == "nonlinearity" and variants:
        form = str(rng.choice(["linear", "quadratic", "axis"]))
        sign = float(rng.choice([-1, 1]))
        if form == "quadratic":
            return {"nonlinearity": {"beta2_per_100N2": 0.01 * sign}}, None, ["beta2_per_100N2"]
        if form == "axis":
            axis = str(rng.choice(list("xyz")))
            return {"nonlinearity": {"beta_per_10N": 0.01 * sign, "axis": axis}}, axis, ["beta_per_10N"]
    if name == "friction":
        return {"friction": {"F_f_N": 1.0}}, None, ["F_f_N"]
    if name == "tare":
        return {"tare": {"tare_kg": 0.1}}, None, ["tare_kg"]
    if name == "creep":
        return {"creep": {"phi": 0.01, "tau_s": float(rng.choice(blind_definitions()["draws"]["creep_tau_s"]))}}, None, \
            ["phi"]
    if name == "nonlinearity":
        return {"nonlinearity": {"beta_per_10N": 0.01 * rng.choice([-1, 1])}}, None, ["beta_per_10N"]
    if name == "crosstalk":
        return {"crosstalk": {"sensor": "z", "eps_y_rad": 0.01 * rng.choice([-1, 1])}}, "sensor:z", ["eps_y_rad"]
    if name == "drift":
        rate = 1e-6 * rng.choice([-1, 1])
        keys = [f"rate_{a}_mm_per_s" for a in "xyz"]
        return {"drift": {k: rate for k in keys}}, "time", keys
    if name == "compliance_scale":
        return {"compliance_scale": {"r": 1.01}}, None, ["r"]
    if name == "torsion_compliance":
        return {"torsion_compliance": {"s_torsion_rad_per_Nm": 1e-6, "point_T_mm": list(places["flange_clamp"][0]),
                                       "axis": [0, 0, 1]}}, "pipe_I", ["s_torsion_rad_per_Nm"]
    draws = blind_definitions()["draws"]
    loc = str(rng.choice(draws["joint_places"]))
    pt, ax = places[loc]
    ratio = float(rng.uniform(*draws["torsion_over_bend"]))
    return {"joint_compliance": {"location": loc, "point_T_mm": list(pt), "axis": list(ax), "s_bend_rad_per_Nm": 1e-6,
                                 "s_torsion_rad_per_Nm": ratio * 1e-6}}, loc, ["s_bend_rad_per_Nm",
                                                                               "s_torsion_rad_per_Nm"]


def peak_change(C, effects, proto) -> float:
    """Largest change an effect makes to the noiseless readings of the gauges the schedule reads."""
    clean = RigModel(C, {}, noise_mm=0.0, resolution_mm=0.0)
    eff = RigModel(C, effects, noise_mm=0.0, resolution_mm=0.0)
    peak, t = 0.0, 0.0
    for k, (axis, rep, phase, mass) in enumerate(proto.holds()):
        h = Hold(k, axis, rep, phase, mass, t)
        read = list(proto.measured.get(axis.value, (0, 1, 2)))
        for dt in (0.0, proto.hold_s * 0.5, proto.hold_s):
            a = clean.reading(t + dt, h)[0][read]
            b = eff.reading(t + dt, h)[0][read]
            peak = max(peak, float(np.max(np.abs(b - a))))
        t += proto.hold_s + proto.gap_s
    return peak


def scaled_effects(effects, keys, factor):
    out = json.loads(json.dumps(effects))
    for name, params in out.items():
        for k in keys:
            if k in params:
                if name == "compliance_scale" and k == "r":
                    params[k] = 1.0 + (params[k] - 1.0) * factor
                else:
                    params[k] = params[k] * factor
    return out


def _wide_schedule(rng) -> LoadSchedule:
    """Protocols beyond the standard batches (``[wide]``: 1-5 repeats, loads along negative axes, holds of 3-30 s
    sampled at 2-20 Hz, gaps of 2-20 s between holds, up to 5 kg)."""
    w = blind_definitions()["wide"]
    axes = tuple(("-" if rng.random() < w["negative_axis"] else "") + a for a in rng.permutation(["y", "z", "x"]))
    hold = float(rng.choice(w["hold_s"]))
    rate = float(rng.choice(w["rate_Hz_long"] if hold >= w["long_hold_s"] else w["rate_Hz"]))
    masses = tuple(w["masses_kg"][int(rng.integers(len(w["masses_kg"])))])
    return LoadSchedule(axes=axes, repeats=int(rng.integers(w["repeats"][0], w["repeats"][1] + 1)), hold_s=hold,
                        rate_Hz=rate, gap_s=float(rng.choice(w["gap_s"])), masses=masses)


def standard_schedule(rng) -> LoadSchedule:
    """The load schedules of the standard batches (``[standard]``)."""
    st = blind_definitions()["standard"]
    return LoadSchedule(axes=tuple(rng.permutation(["y", "z", "x"])),
                        repeats=int(rng.integers(st["repeats"][0], st["repeats"][1] + 1)),
                        hold_s=float(rng.choice(st["hold_s"])),
                        masses=tuple(st["masses_kg"][int(rng.integers(len(st["masses_kg"])))]))


def _kind(u: float) -> str:
    """The kind of a case from a uniform draw ``u`` (``[mix]``: cumulative bounds)."""
    mix = blind_definitions()["mix"]
    return ("null" if u < mix["null"] else "single" if u < mix["single"] else "pair" if u < mix["pair"]
            else "decoy" if u < mix["decoy"] else "oolib")


def generate_cases(out_dir, n: int = 60, seed: int = 1000, rod="rod1", wide: bool = False,
                   variants: bool = False) -> list[BlindCase]:
    """``n`` blind cases of ``rod`` (a built-in name or a design); ``wide``: draw the load schedules from
    :func:`_wide_schedule` (other repeats, signs, hold
    times, sample rates, gaps and loads) instead of the standard ones; ``variants``: other forms of the effects
    (:func:`unit_effect`), an effect beside a bumped hold, and more effects outside the library (a gauge that
    slips once, a gauge that saturates)."""
    rng = np.random.default_rng(seed)
    draws = blind_definitions()["draws"]
    design = resolve_design(rod) if isinstance(rod, str) else rod
    C = calc_rod_compliance(design).C_F
    places = joint_places(design.tool_mm, design)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cases = []
    for i in range(n):
        kind = _kind(rng.random())
        noise = float(rng.choice(draws["noise_mm"]))
        proto = _wide_schedule(rng) if wide else standard_schedule(rng)
        effects, truth_effects = {}, []
        names = [] if kind in ("null", "decoy", "oolib") else list(rng.choice(LIBRARY, 1 if kind == "single" else 2,
                                                                           replace=False))
        for name in names:
            first = unit_effect(name, rng, places, variants)
            snr = float(np.exp(rng.uniform(*np.log(draws["snr"]))))
            unit, loc, keys, scaled, snr = _visible_effect(first, name, rng, places, variants, C, proto, snr, noise)
            effects.update(scaled)
            truth_effects.append({"effect": name, "location": loc, "snr": snr, "parameters": scaled[name]})
        model = RigModel(C, effects, noise_mm=noise, resolution_mm=0.001 if noise >= 0.0006 else 0.0001,
                         seed=int(rng.integers(1 << 30)), temp_amplitude_K=float(rng.uniform(*draws["temp_amplitude_K"])))
        path = out / f"case{i:03d}.rig.csv"
        simulate_recording(model, proto, path, rod=design.name)
        expected = "consistent" if not truth_effects else "explained"
        if kind == "decoy":
            _decoy(path, rng)
            truth_effects = []
            expected = "consistent|unexplained"
        outside = None
        if kind == "oolib":
            outside = out_of_library(path, rng, noise, variants)
            expected = "unexplained"
        if variants and kind == "single" and rng.random() < draws["variants_decoy"]:   # beside a bumped hold
            _decoy(path, rng)
            kind = "single+decoy"
        truth = {"kind": kind, "effects": truth_effects, "expected_verdict": expected, "noise_mm": noise, "outside": outside,
                 "protocol": {"axes": list(proto.axes), "repeats": proto.repeats, "masses": list(proto.masses),
                              "hold_s": proto.hold_s, "rate_Hz": proto.rate_Hz, "gap_s": proto.gap_s}}
        (out / f"case{i:03d}.truth.json").write_text(json.dumps(truth, indent=1))
        cases.append(BlindCase(path, truth))
    return cases


def _rewrite(path, fn):
    lines = path.read_text().splitlines()
    head = [l for l in lines if l.startswith("#") or l.startswith("time_s")]
    rows = [l.split(",") for l in lines if l and not l.startswith("#") and not l.startswith("time_s")]
    fn(rows)
    path.write_text("\n".join(head + [",".join(r) for r in rows]) + "\n")


def _decoy(path, rng):
    """A bumped hold (one hold shifted by a few um) - one isolated outlier hold."""
    bump = blind_definitions()["decoy"]["bump_mm"]

    def fn(rows):
        steps = sorted({int(r[1]) for r in rows})
        s = int(rng.choice(steps[5:]))
        for r in rows:
            if int(r[1]) == s:
                for c in (6, 7, 8):
                    if r[c]:
                        r[c] = f"{float(r[c]) + bump:.4f}"
    _rewrite(path, fn)


#: the largest tilt a crosstalk variant is drawn with [rad] (the hypothesis's bound is 0.2 rad): a stronger one
#: is drawn at this tilt, at the signal-to-noise ratio it then has
_MAX_BLIND_TILT = 0.15


def _visible_effect(first, name, rng, places, variants, C, proto, snr, noise):
    """(unit effect, location, keys, effect scaled to change the read gauges by ``snr`` x ``noise`` at most, the
    ratio drawn) from the ``first`` draw of :func:`unit_effect`. A crosstalk variant that the schedule's gauges do
    not see (a load tilted towards an axis none of its series' gauges reads) is drawn again; one that would need a
    tilt beyond :data:`_MAX_BLIND_TILT` is drawn at that tilt."""
    for attempt in range(20):
        unit, loc, keys = first if attempt == 0 else unit_effect(name, rng, places, variants)
        pk = peak_change(C, unit, proto)
        if pk <= 1e-9:
            continue
        factor = snr * noise / pk
        if name == "crosstalk" and variants:
            tilt = max(abs(unit[name][k]) for k in keys)
            factor = min(factor, _MAX_BLIND_TILT / tilt)
        return unit, loc, keys, scaled_effects(unit, keys, factor), factor * pk / noise
    raise RigError(f"blind cases: no form of {name} that this schedule's gauges see in 20 draws", key="blind")


def _crosstalk_variant(rng):
    """A tilted gauge or a tilted load line, either towards a random other axis (the schedules read the z gauge
    under every load axis, x under x and z, y under y)."""
    sign = float(rng.choice([-1, 1]))
    if rng.random() < 0.5:
        sensor = str(rng.choice(list("xz")))
        towards = str(rng.choice([a for a in "xyz" if a != sensor]))
        return {"crosstalk": {"sensor": sensor, f"eps_{towards}_rad": 0.01 * sign}}, f"sensor:{sensor}", \
            [f"eps_{towards}_rad"]
    load = str(rng.choice(list("xyz")))
    towards = str(rng.choice([a for a in "xyz" if a != load]))
    return {"crosstalk": {"load": load, f"eps_{towards}_rad": 0.01 * sign}}, f"load:{load}", [f"eps_{towards}_rad"]


def out_of_library(path, rng, noise, variants: bool = False):
    """Gauge non-linearity (quadratic in the reading) or mains hum: not in the library; with ``variants`` also a
    gauge that slips once (a step of 15 noise SDs from a random time on, one gauge) or saturates (readings
    clipped at 70 % of that gauge's largest). Returns the variant's name. The quadratic term is at least
    ``quadratic_min_noise_sd`` noise SDs at the largest reading (on a stiff rod 0.004/mm alone is nanometres)."""
    o = blind_definitions()["outside"]
    which = rng.choice(["quadratic", "hum", "slip", "saturation"] if variants else ["quadratic", "hum"])
    t_slip, col, series = 0.0, 6, None
    if which in ("slip", "saturation"):            # (drawn only then: the older batches keep their draws)
        data = [line.split(",") for line in path.read_text().splitlines() if line[:1].isdigit()]
        t_slip = float(rng.uniform(*o["slip_time"])) * float(data[-1][0])
        # a slip of a gauge that is not read from then to the end of its series would not be there: the gauge that
        # slips is one being read at that moment (a series zeroes its gauges)
        now = next(r for r in data if float(r[0]) >= t_slip)
        col = int(rng.choice([c for c in (6, 7, 8) if now[c]] if which == "slip" else [6, 7, 8]))
        series = now[4]                            # the load axis: the slip lasts to the end of its series

    def fn(rows):
        vmax = max((abs(float(r[col])) for r in rows if r[col]), default=0.0)
        vall = max((abs(float(r[c])) for r in rows for c in (6, 7, 8) if r[c]), default=0.0)
        k = max(o["quadratic_per_mm"], o.get("quadratic_min_noise_sd", 0.0) * noise / max(vall * vall, 1e-12))
        for r in rows:
            t = float(r[0])
            for c in (6, 7, 8):
                if not r[c]:
                    continue
                v = float(r[c])
                if which == "quadratic":
                    v += k * v * v
                elif which == "hum":
                    v += o["hum_noise_sd"] * noise * np.sin(2 * np.pi * t / o["hum_period_s"])
                elif which == "slip" and c == col and t >= t_slip and r[4] == series:
                    v += o["slip_noise_sd"] * noise
                elif which == "saturation" and c == col:
                    v = float(np.clip(v, -o["saturation"] * vmax, o["saturation"] * vmax))
                r[c] = f"{v:.4f}"
    _rewrite(path, fn)
    return str(which)
