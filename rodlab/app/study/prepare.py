"""What a study knows of one design before any campaign is simulated: its compliance files (the joint-
calibrated frame as FEA, the closed form as Calc), mass and c_rod, the planned rod orientations with their
observability on the robot, thermal growth, natural frequencies and strength margins."""
from __future__ import annotations

import logging
import math
import re
from dataclasses import dataclass, field

import numpy as np

from rodlab.calibrate import CalibrationError, Rod
from rodlab.calibrate.plan import plan_poses
from rodlab.core.calc import calc_rod_compliance
from rodlab.core.compliance import RodCompliance
from rodlab.core.enums import DesignStatus
from rodlab.core.errors import RodlabError
from rodlab.core.strength import strength_margins, thermal_growth_um_per_K
from rodlab.fea import compute_compliance
from rodlab.fea.modal import frame_frequencies

from .designs import Candidate

__all__ = ["DesignSetup", "prepare_design", "study_reason"]

log = logging.getLogger(__name__)


@dataclass
class DesignSetup:
    """One design's fixed quantities (see the module docstring); ``plan_q_rad`` {position: (k, n) [rad]}."""

    label: str
    L1_mm: float
    L2_mm: float
    material: str
    tube: str
    status: DesignStatus
    message: str = ""
    fea: RodCompliance | None = None
    calc: RodCompliance | None = None
    compliance_model: str = ""
    plan_q_rad: dict = field(default_factory=dict)
    observability: dict = field(default_factory=dict)
    r_prior: tuple = (1.0, 1.0)
    thermal_um_per_K: tuple = (math.nan, math.nan, math.nan)
    frequencies_Hz: tuple = (math.nan, math.nan, math.nan)
    strength: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.status = DesignStatus.parse(self.status, "design status")

    @property
    def ok(self) -> bool:
        return self.status is DesignStatus.OK

    def to_dict(self) -> dict:
        d = {k: getattr(self, k) for k in ("label", "L1_mm", "L2_mm", "material", "tube", "message",
                                           "compliance_model", "observability", "strength")}
        d["status"] = str(self.status)
        d.update(fea=self.fea.to_dict() if self.fea else None, calc=self.calc.to_dict() if self.calc else None,
                 plan_q_rad={str(j): np.asarray(q).tolist() for j, q in self.plan_q_rad.items()},
                 r_prior=list(self.r_prior), thermal_um_per_K=[float(v) for v in self.thermal_um_per_K],
                 frequencies_Hz=[float(v) for v in self.frequencies_Hz])
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "DesignSetup":
        kw = dict(d)
        kw["fea"] = RodCompliance.from_dict(d["fea"]) if d.get("fea") else None
        kw["calc"] = RodCompliance.from_dict(d["calc"]) if d.get("calc") else None
        kw["plan_q_rad"] = {int(j): np.asarray(q, float) for j, q in d.get("plan_q_rad", {}).items()}
        for k in ("r_prior", "thermal_um_per_K", "frequencies_Hz"):
            kw[k] = tuple(float("nan") if v is None else float(v) for v in d[k])
        kw["strength"] = {k: float("nan") if v is None else v for k, v in d.get("strength", {}).items()}
        return cls(**kw)


def _compliance(design, joints):
    fea = compute_compliance(design, "frame", **({"calibration": joints} if joints is not None else {}))
    model = "frame, joint-calibrated on solid FEA" if joints is not None else "frame (global calibration)"
    return fea, calc_rod_compliance(design), model


def _physics(design, force_N: float) -> dict:
    sm = strength_margins(design, force_N)
    return {"thermal_um_per_K": tuple(float(v) for v in thermal_growth_um_per_K(design)),
            "frequencies_Hz": tuple(float(v) for v in frame_frequencies(design, modes=3)),
            "strength": {"tube_stress_MPa": sm.tube_stress_MPa, "tube_margin": sm.tube_margin, "tube_at": sm.tube_at,
                         "bond_stress_MPa": sm.bond_stress_MPa, "bond_margin": sm.bond_margin,
                         "bond_at": sm.bond_at, "load_N": sm.force_N}}


def prepare_design(cand: Candidate, robot, fixture, orientations: int, r_prior, joints=None, seed: int = 0,
                   candidates: int = 30, base=None) -> DesignSetup:
    """Everything of ``cand`` that does not depend on a replicate; a design the robot cannot use, or whose
    computation fails, is a setup with that status and the reason (never an exception). ``base``: the robot base
    {0} in {W} [mm, deg] (None: the simulator's standard layout)."""

    row = dict(label=cand.label, L1_mm=cand.L1_mm, L2_mm=cand.L2_mm, material=cand.material, tube=cand.tube)
    if cand.design is None:
        return DesignSetup(**row, status=DesignStatus.INVALID, message=cand.invalid)
    d = cand.design
    try:
        fea, calc, model = _compliance(d, joints)
        extras = _physics(d, float(np.linalg.norm(fixture.force_D_N)))
    except (RodlabError, ValueError, np.linalg.LinAlgError) as e:
        return DesignSetup(**row, status=DesignStatus.FAILED, message=f"{type(e).__name__}: {e}")
    setup = DesignSetup(**row, status=DesignStatus.OK, fea=fea, calc=calc, compliance_model=model,
                        r_prior=tuple(r_prior), **extras)
    notes = fea.provenance.get("outside_calibrated_range") or []
    if notes:                      # the global frame off its calibrated range: said on the row (fea and sweep say it)
        setup.message = "frame: " + "; ".join(notes) + "; check this design with `rodlab fea --model solid`"
    try:
        # the study's poses are not yet held to the device's open side (calibrate.plan.ROD_ANGLE_MAX_DEG): with it
        # the predicted compensation gains move within their seed-to-seed scatter (rod 6#'s 0.005-0.018 mm), and
        # the study's pages and its Table 3 comparison were made without it
        q_deg, obs = plan_poses(robot, fixture, Rod.rigid(d.tool_mm, fea.mass_kg, fea.com_T_mm), k=orientations,
                                candidates=candidates, seed=seed, max_rod_angle_deg=None, base_guess=base)
    except CalibrationError as e:
        setup.status, setup.message = DesignStatus.UNREACHABLE, f"{robot.name} with this rod: {e}"
        return setup
    setup.plan_q_rad = {int(j): np.deg2rad(q) for j, q in q_deg.items()}
    setup.observability = {k: float(v) for k, v in obs.items()}
    return setup


def study_reason(e: Exception) -> str:
    """A prediction's refusal in a designer's terms: a campaign that cannot identify the robot's parameters is told
    what about the rod causes it and what to change (the identification's own advice, ``--pin`` / ``--strict``, is
    a calibration's, which ``rodlab study`` has not)."""
    text = str(e)
    found = re.search(r"cannot identify (\d+) parameter\(s\): (.*?)\. (Add|Measure)", text)
    if not found:
        return f"prediction: {text}"
    return (f"prediction: the planned campaign cannot identify {found.group(1)} parameter(s) of the robot with this "
            f"rod ({found.group(2)}): the rod's poses leave them unseen; a straight rod (gamma 180) puts the ball on "
            "the flange's axis, where the last joint's turn moves nothing: give it a bend (gamma below 180), or plan "
            "more rod orientations (--orientations)")
