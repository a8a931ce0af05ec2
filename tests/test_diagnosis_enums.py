"""A diagnosis' verdict, subject and finding effects are Enums (``Verdict``, ``Subject``, ``FindingKind`` of
rodlab.core.enums; the effect IDs the registries' ``RigEffect`` and ``CampaignEffect``), parsed from the contract
spelling, and its report file holds exactly the contract spelling (plain JSON strings, byte for byte)."""
from __future__ import annotations

import json

import pytest

from rodlab.app.diagnose import diagnose_rig
from rodlab.app.diagnose.report import Diagnosis, Finding
from rodlab.app.diagnose.effect_ids import parse_effect_id
from rodlab.calibrate.effects import CampaignEffect
from rodlab.core.enums import FindingKind, Subject, Verdict
from rodlab.core.errors import RodlabError
from rodlab.core.schema import load_schema
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.effects import RigEffect

from conftest import legacy_design


def _plain(obj) -> bool:
    """Only JSON's own Python types (no Enum, no NumPy) anywhere in ``obj``."""
    if isinstance(obj, dict):
        return all(type(k) is str and _plain(v) for k, v in obj.items())
    if isinstance(obj, list):
        return all(_plain(v) for v in obj)
    return obj is None or type(obj) in (str, int, float, bool)


def test_verdict_and_subject_are_the_schema_enums():
    schema = load_schema("rodlab.diagnosis/1")["properties"]
    assert [v.value for v in Verdict] == schema["verdict"]["enum"]
    assert [s.value for s in Subject] == schema["subject"]["enum"]


def test_effect_ids_parse_into_one_enum_each_and_unknown_ones_are_refused():
    ids = [*RigEffect, *CampaignEffect, *FindingKind]
    assert len({e.value for e in ids}) == len(ids)          # no spelling names two things
    for e in ids:
        assert parse_effect_id(e.value) is e and parse_effect_id(e) is e
    with pytest.raises(RodlabError, match="frictoin.*friction"):
        parse_effect_id("frictoin")
    with pytest.raises(RodlabError, match="verdict"):
        Diagnosis("rig", "maybe", 0.001, 0.002, 0.001, [])


def test_report_holds_the_contract_spelling_byte_for_byte(tmp_path):
    """A simulated friction recording: the objects hold Enums, the file the same bytes as the report written
    from plain strings."""
    from rodlab import calc_rod_compliance
    from rodlab.stiffness_rig.model import LoadSchedule, RigModel
    from rodlab.stiffness_rig.simulate import simulate_recording
    design = legacy_design("rod1")
    sim = calc_rod_compliance(design)
    path = tmp_path / "r.rig.csv"
    simulate_recording(RigModel(sim.C_F, {"friction": {}}, noise_mm=0.001, resolution_mm=0.001, seed=3),
                       LoadSchedule(axes=("z", "x", "y"), repeats=3, hold_s=5.0, masses=(0.5, 1.0, 1.5)), path,
                       rod=design.name)
    diag, _ = diagnose_rig(read_recording(path), sim, design, accuracy="exact")
    assert diag.subject is Subject.RIG and diag.verdict is Verdict.EXPLAINED
    assert diag.findings[0].effect is RigEffect.FRICTION
    d = diag.to_dict()
    assert _plain(d)
    assert d["subject"] == "rig" and d["verdict"] == "explained" and d["findings"][0]["effect"] == "friction"
    text = diag.write(tmp_path / "d.json").read_text()
    strings = Diagnosis(str(diag.subject.value), str(diag.verdict.value), diag.noise_mm, diag.rms_before_mm,
                        diag.rms_after_mm, [Finding.from_dict(f) for f in d["findings"]], diag.extra)
    assert strings.write(tmp_path / "s.json").read_text() == text
    assert json.loads(text)["findings"] == d["findings"]
