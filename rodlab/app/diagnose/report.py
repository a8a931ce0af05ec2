"""The diagnosis report (contract ``rodlab.diagnosis/1``) and its findings."""
from __future__ import annotations

import math

from dataclasses import dataclass, field
from pathlib import Path

from ...core.enums import Subject, Verdict
from ...core.fileio import atomic_write_json, json_safe
from .effect_ids import EffectId, parse_effect_id

__all__ = ["Finding", "Diagnosis", "FORMAT_DIAGNOSIS"]

FORMAT_DIAGNOSIS = "rodlab.diagnosis/1"


@dataclass
class Finding:
    """One effect: ID and location (contract vocabulary), one sentence of physics, fitted parameters with
    95 % intervals, the fit before / after adding it, and the evidence (delta BIC, LR test, CV)."""

    effect: EffectId        # the contract spelling is parsed: RigEffect, CampaignEffect or FindingKind
    location: str | None
    explanation: str
    parameters: dict
    intervals: dict
    rms_before_mm: float
    rms_after_mm: float
    evidence: dict = field(default_factory=dict)

    def __post_init__(self):
        self.effect = parse_effect_id(self.effect)

    @classmethod
    def from_dict(cls, f: dict) -> "Finding":
        """A finding as read back from a diagnosis report (the inverse of :meth:`to_dict`)."""
        return cls(f["effect"], f["location"], f["explanation"], f["parameters"], f.get("intervals_95", {}),
                   f["rms_before_mm"], f["rms_after_mm"], f.get("evidence", {}))

    def to_dict(self) -> dict:
        params = dict(self.parameters)
        return {"effect": self.effect.value, "location": self.location, "explanation": self.explanation,
                "parameters": params, "intervals_95": self.intervals, "rms_before_mm": self.rms_before_mm,
                "rms_after_mm": self.rms_after_mm, "evidence": self.evidence}


@dataclass
class Diagnosis:
    """A diagnosis report: what was looked at, the verdict, the noise and fit before / after the findings."""

    subject: Subject
    verdict: Verdict
    noise_mm: float
    rms_before_mm: float
    rms_after_mm: float
    findings: list
    extra: dict = field(default_factory=dict)

    def __post_init__(self):
        self.subject = Subject.parse(self.subject, "diagnosis subject")
        self.verdict = Verdict.parse(self.verdict, "verdict")

    def to_dict(self) -> dict:
        return json_safe({"format": FORMAT_DIAGNOSIS, "subject": self.subject.value, "verdict": self.verdict.value,
                          "noise_mm": self.noise_mm, "rms_before_mm": self.rms_before_mm,
                          "rms_after_mm": self.rms_after_mm, "findings": [f.to_dict() for f in self.findings],
                          **self.extra})

    def write(self, path: str | Path) -> Path:
        return atomic_write_json(path, self.to_dict())

    def summary(self) -> str:
        from .wording import caution, confirmation, evidence_text   # cycle: wording imports Finding from this module
        refit = (" (identified again with the findings; each finding's own share below is on the first fit's "
                 "residuals)" if self.subject == Subject.CAMPAIGN and self.findings else "")
        lines = [f"verdict: {self.verdict} ({self.subject}); noise {self.noise_mm * 1e3:.2f} um per reading; "
                 f"rms {self.rms_before_mm * 1e3:.2f} -> {self.rms_after_mm * 1e3:.2f} um{refit}"]
        if self.extra.get("gross_text"):
            lines.append(f"  gross readings: {self.extra['gross_text']}")
        if self.extra.get("settling_text"):
            lines.append(f"  settling: {self.extra['settling_text']}")
        if "repeatability_mm" in self.extra:
            x = self.extra
            lines.append(f"  repeatability: the hold means scatter {x['repeatability_mm'] * 1e3:.2f} um from one repeat to "
                         f"the next ({x['repeat_scatter_x_noise']:.1f} x the noise of a hold's mean), no misfit shared "
                         f"by the repeats detected (p = {x['shared_misfit_p']:.2g}; the largest, p = "
                         f"{x['worst_group_p']:.2g}): the rig's repeatability (re-seating, friction from hold to hold), "
                         "against which the effects were judged")
        for i, f in enumerate(self.findings, 1):
            bound = set(f.evidence.get("at_bound", ()))
            ps = ", ".join(f"{k} = {v:.4g} " + ("(at its bound: the data ask for more; no interval)" if k in bound else
                                                _interval_text(*f.intervals[k]))
                           for k, v in f.parameters.items() if isinstance(v, (int, float)) and k in f.intervals)
            lines.append(f"  {i}. {f.effect}" + (f" at {f.location}" if f.location else "") + f": {f.explanation}")
            if ps:
                lines.append(f"     {ps}")
            ev = f.evidence
            lines.append(f"     {evidence_text(f)}")
            if ev.get("alternatives"):
                lines.append("     the data fit about as well with: " + "; ".join(ev["alternatives"]))
            if caution(f):
                lines.append(f"     caution: {caution(f)}")
            lines.append(f"     {'to confirm' if self.subject == Subject.RIG else 'next step'}: {confirmation(f)}")
        if self.extra.get("refit_warning"):
            lines.append(f"  warning: {self.extra['refit_warning']}")
        return "\n".join(lines)


def _interval_text(lo: float, hi: float) -> str:
    """``[lo, hi]`` with the digits that tell its ends apart (a trial: r_11 [1.07, 1.07]), at least three."""
    scale = max(abs(lo), abs(hi))
    width = abs(hi - lo)
    digits = 3 if width == 0 or scale == 0 else int(min(8, max(3, math.ceil(math.log10(scale / width)) + 2)))
    return f"[{lo + 0.0:.{digits}g}, {hi + 0.0:.{digits}g}]"            # + 0.0: no "-0"
