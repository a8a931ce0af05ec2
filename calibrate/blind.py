"""Blind calibration campaigns with a known truth, for scoring the campaign diagnosis on data it never saw.

Generated with the campaign simulator (:func:`~rodlab.calibrate.simulate.simulate_campaign`, never diagnosis
code) from the definitions in ``calibrate/blind_cases.toml``: the kinds drawn in turn (a null, one effect of the
campaign effect registry, or a pair) and the size of each. Gross alignment errors are written into the
campaign file after simulation with the cases' own generator, so that the rest of a case does not depend on
them. ``benchmarks/campaign_blind.py`` diagnoses and scores these cases.
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources
from pathlib import Path

import numpy as np

from rodlab.core.schema import read_toml_checked

from .errors import CalibrationError
from .simulate import CampaignSpec, simulate_campaign

__all__ = ["CampaignCase", "BlindDefinitions", "blind_definitions", "read_blind_definitions", "kind_effects",
           "generate_campaign_cases", "FORMAT_BLIND"]

FORMAT_BLIND = "rodlab.blind_campaign/1"


@dataclass(frozen=True)
class BlindDefinitions:
    """The blind-case definitions (``calibrate/blind_cases.toml``).

    kinds : the kinds drawn in turn; modes : {mode: extra kinds}; magnitudes : {name: value or [min, max]}
    (see the file for units); wide : {name: [min, max]} of the per-case protocol of mode ``wide``
    """

    kinds: tuple
    modes: dict
    magnitudes: dict
    wide: dict

    def kinds_of(self, mode: str) -> list[str]:
        if mode and mode not in self.modes:
            raise CalibrationError(f"unknown blind-case mode {mode!r}; expected one of {sorted(self.modes)}",
                                   key="mode")
        return list(self.kinds) + list(self.modes.get(mode, []))


def read_blind_definitions(path) -> BlindDefinitions:
    """Blind-case definitions from ``path`` (``rodlab.blind_campaign/1``); every schema problem named at once
    (file, line, key)."""
    data, _ = read_toml_checked(path, FORMAT_BLIND, CalibrationError)
    return BlindDefinitions(tuple(data["kinds"]), dict(data["modes"]), dict(data["magnitudes"]), dict(data["wide"]))


@lru_cache(maxsize=None)
def blind_definitions() -> BlindDefinitions:
    """The shipped definitions (``calibrate/blind_cases.toml``)."""
    return read_blind_definitions(Path(str(resources.files("rodlab.calibrate").joinpath("blind_cases.toml"))))


@dataclass(frozen=True)
class CampaignCase:
    """One blind campaign: its folder (``multical.campaign.csv``, ``.fixture.json``, ``.validation.csv``), the
    device noise stated to the diagnosis [mm], and its truth (kind, effect, location, magnitudes, points moved,
    protocol)."""

    folder: Path
    noise_mm: float
    truth: dict


def generate_campaign_cases(robot, rod, out_dir, n: int, seed: int, mode: str = "") -> list[CampaignCase]:
    """``n`` blind campaigns of ``robot`` with ``rod`` in ``out_dir/c{i}``; ``mode``: ``""``, ``pairs`` or
    ``wide`` (the pair with an outlier inside the misclamped position, and the protocol drawn per case)."""
    defs = blind_definitions()
    kinds = defs.kinds_of(mode)
    rng = np.random.default_rng(seed)
    cases = []
    for i in range(n):
        cases.append(_case(robot, rod, Path(out_dir) / f"c{i}", kinds[i % len(kinds)], mode, defs, rng))
    return cases


def _case(robot, rod, out: Path, kind: str, mode: str, defs: BlindDefinitions, rng) -> CampaignCase:
    mag, wide = defs.magnitudes, defs.wide
    truth = {"kind": kind, "effect": None if kind == "null" else kind}
    protocol = {}
    if mode == "wide":
        protocol = {"positions": int(rng.integers(wide["positions"][0], wide["positions"][1] + 1)),
                    "orientations": int(rng.integers(wide["orientations"][0], wide["orientations"][1] + 1)),
                    "device_noise_mm": round(float(rng.uniform(*wide["device_noise_mm"])), 4)}
    effects = _effects(kind, protocol.get("positions", 5), len(robot.a_mm), mag, truth, rng)
    spec = CampaignSpec(seed=int(rng.integers(1 << 30)), **protocol)
    truth["protocol"] = f"{spec.positions}x{spec.orientations}, {spec.device_noise_mm * 1e3:.1f} um"
    simulate_campaign(robot, rod, out, spec, effects=effects)
    if kind.endswith("outliers"):
        truth["points"] = add_gross_errors(out / "multical.campaign.csv", rng, mag["outliers"], mag["outlier_mm"])
    if kind.endswith("outlier_inside"):                # one of them inside the misclamped position
        truth["points"] = add_gross_errors(out / "multical.campaign.csv", rng, mag["outliers"], mag["outlier_mm"],
                                           int(truth["location"].split(":")[1]))
    return CampaignCase(out, spec.device_noise_mm, truth)


#: blind kinds that are a form of one registry effect rather than its name
KIND_FORMS = {"periodic_both": "periodic_joint_error", "outlier_inside": "outliers"}


def kind_effects(kind: str) -> list[str]:
    """The registry effects (contract spelling) a blind kind injects: ``null`` none, a pair ``a+b`` both, a form
    (:data:`KIND_FORMS`: ``periodic_both``, a gear with both harmonics) its effect."""
    return [] if kind == "null" else [KIND_FORMS.get(k, k) for k in kind.split("+")]


def _effects(kind: str, npos: int, n_joints: int, mag: dict, truth: dict, rng) -> list:
    """The (name, parameters) of the campaign effect registry a case of ``kind`` injects; fills ``truth``."""
    effects = []
    if kind.startswith("fixture_pose"):               # any position but the world one (1 + npos // 2)
        j = int(rng.choice([p for p in range(1, npos + 1) if p != 1 + npos // 2]))
        effects.append(("fixture_pose", {"position": j,
                                         "offset_mm": list(rng.normal(0, mag["fixture_offset_sd_mm"], 3))}))
        truth["location"] = f"position:{j}"
    if kind == "rod_deflection":
        k = float(rng.choice(mag["rod_k"]))
        effects.append(("rod_deflection", {"k": k}))
        truth["k"] = k
    if kind == "periodic_joint_error":
        k = int(rng.integers(1, n_joints + 1))
        amp = float(rng.choice([-1, 1]) * rng.uniform(*mag["periodic_amp_deg"]))
        phase = float(rng.uniform(0, 360))
        effects.append(("periodic_joint_error", {"joint": k, "amp_deg": amp, "phase_deg": phase}))
        truth["location"] = f"joint:{k}"
        truth["amp_deg"] = amp
    if kind == "joint_zero_shift":                    # joints 2..n: joint 1's is a translation of the position
        j, k = int(rng.integers(1, npos + 1)), int(rng.integers(2, n_joints + 1))
        d = float(rng.choice([-1, 1]) * rng.uniform(*mag.get("zero_shift_deg", (0.004, 0.012))))
        effects.append(("joint_zero_shift", {"position": j, "joint": k, "dtheta_deg": d}))
        truth.update(location=f"position:{j}", joint=k, dtheta_deg=d)
    if kind == "periodic_both":                       # a joint that turns a revolution in the campaign
        k = int(rng.choice([4, 6]))
        amp = float(rng.choice([-1, 1]) * rng.uniform(*mag["periodic_amp_deg"]))
        amp2 = float(rng.uniform(*mag.get("periodic2_amp_deg", (0.003, 0.008))))
        effects.append(("periodic_joint_error", {"joint": k, "amp_deg": amp, "phase_deg": float(rng.uniform(0, 360)),
                                                 "amp2_deg": amp2, "phase2_deg": float(rng.uniform(0, 360))}))
        truth.update(location=f"joint:{k}", amp_deg=amp, amp2_deg=amp2)
    if kind == "thermal_drift":
        therm = float(rng.uniform(*mag["thermal_ppm_per_s"]))
        effects.append(("thermal_drift", {"growth_ppm_per_s": therm}))
        truth["location"] = "time"
        truth["ppm_per_s"] = therm
    return effects


def add_gross_errors(path: Path, rng, k: int, size_mm, inside: int | None = None) -> list[str]:
    """Move ``k`` random points of a campaign file by +-U(``size_mm``) on each reading axis (with ``inside``:
    the first at that clamping position); returns their labels ``position.orientation``."""
    rows = list(csv.reader(path.read_text().splitlines()))
    if inside is None:
        idx = rng.choice(np.arange(1, len(rows)), size=k, replace=False)
    else:
        at = [i for i in range(1, len(rows)) if rows[i][0] == str(inside)]
        rest = [i for i in range(1, len(rows)) if rows[i][0] != str(inside)]
        idx = [int(rng.choice(at))] + [int(i) for i in rng.choice(rest, size=k - 1, replace=False)]
    labels = []
    for i in idx:
        for c in (-5, -4, -3):
            rows[i][c] = f"{float(rows[i][c]) + rng.choice([-1, 1]) * rng.uniform(*size_mm):.4f}"
        labels.append(f"{rows[i][0]}.{rows[i][1]}")
    path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    return labels
