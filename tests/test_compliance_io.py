"""Compliance files: round trip, contract example, Eq. 21/23, and every reader check."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab import ComplianceError, Method, RodCompliance, c_rod_um, load_design, r_rod, read_compliance, \
    write_compliance
from rodlab.calc import calc_rod_compliance

from conftest import ROD1


@pytest.fixture
def comp() -> RodCompliance:
    return calc_rod_compliance(load_design(ROD1))


def test_round_trip(tmp_path, comp):
    p = write_compliance(comp, tmp_path / "a.compliance.json")
    back = read_compliance(p)
    np.testing.assert_allclose(back.C_F, comp.C_F, rtol=1e-8)
    np.testing.assert_allclose(back.C_g, comp.C_g, rtol=1e-8)
    assert back.method is Method.CALC and back.mass_kg == pytest.approx(comp.mass_kg)
    assert back.provenance["design_sha256"] == comp.provenance["design_sha256"]
    assert not list(tmp_path.glob(".*.tmp"))   # atomic write leaves no temp file
    data = json.loads(p.read_text())
    assert data["c_rod_um"] == pytest.approx(comp.c_rod_um, rel=1e-6)


def test_reads_contract_example_and_eq23(examples):
    c = read_compliance(examples / "rod1.compliance.json")
    stored = json.loads((examples / "rod1.compliance.json").read_text())["c_rod_um"]
    assert c.c_rod_um == pytest.approx(stored, abs=0.01)


def test_eq21_and_eq23_by_hand():
    CF = np.diag([1.0, 2.0, 3.0]) * 1e-3
    Cg = np.full((3, 3), 1e-3)
    f = np.linalg.norm([1.10, 1.25, 1.05])
    assert c_rod_um(CF, Cg) == pytest.approx(9.0 + 6.0 * f)
    assert c_rod_um(CF, Cg, force_N=2.0) == pytest.approx(21.0)
    assert r_rod(CF * 1.3, CF) == pytest.approx(1.3)
    with pytest.raises(ComplianceError):
        r_rod(CF, np.zeros((3, 3)))


def test_offset_eq19(comp):
    g = np.array([[0, 0, -1.0], [1.0, 0, 0]])
    F = np.array([[1.0, 2.0, 3.0], [0, 0, 0]])
    off = comp.offset_T_mm(g, F)
    np.testing.assert_allclose(off[0], comp.C_g @ g[0] + comp.C_F @ F[0])
    np.testing.assert_allclose(off[1], comp.C_g[:, 0])


def test_none_like(comp):
    n = RodCompliance.none_like(comp)
    assert n.method is Method.NONE and not n.C_F.any() and n.mass_kg == comp.mass_kg


def _bad(tmp_path, comp, mutate, text=None):
    data = comp.to_dict()
    mutate(data)
    p = tmp_path / "bad.compliance.json"
    p.write_text(text if text is not None else json.dumps(data, indent=1))
    return p


CASES = [
    ("missing key", lambda d: d.pop("C_g_mm_per_g0"), "C_g_mm_per_g0", "missing"),
    ("format", lambda d: d.update(format="rodlab.compliance/0"), "format", "rodlab.compliance/1"),
    ("method", lambda d: d.update(method="fem"), "method", "fea"),
    ("shape", lambda d: d.update(C_F_mm_per_N=[[1, 0], [0, 1]]), "C_F_mm_per_N", "3 items"),
    ("non-numeric", lambda d: d.update(C_g_mm_per_g0=[["a", 0, 0], [0, 1, 0], [0, 0, 1]]), "C_g_mm_per_g0",
     "a number"),
    ("nan", lambda d: d["C_F_mm_per_N"][0].__setitem__(0, float("nan")), "C_F_mm_per_N", "finite"),
    ("asymmetric", lambda d: d["C_F_mm_per_N"][0].__setitem__(2, 0.01), "C_F_mm_per_N", "symmetric"),
    ("not psd", lambda d: d["C_F_mm_per_N"][1].__setitem__(1, -0.2), "C_F_mm_per_N", "semi-definite"),
    ("none nonzero", lambda d: d.update(method="none"), "method", "zero matrices"),
    ("mass", lambda d: d.update(mass_kg=-1), "mass_kg", "> 0"),
    ("mass type", lambda d: d.update(mass_kg="heavy"), "mass_kg", "number"),
    ("tool", lambda d: d.update(tool_mm=[1, 2]), "tool_mm", "3 items"),
    ("r_rod", lambda d: d.update(r_rod=0), "r_rod", "> 0"),
]


@pytest.mark.parametrize("label,mutate,key,words", CASES, ids=[c[0] for c in CASES])
def test_reader_rejects(tmp_path, comp, label, mutate, key, words):
    p = _bad(tmp_path, comp, mutate)
    with pytest.raises(ComplianceError) as ei:
        read_compliance(p)
    assert ei.value.key.startswith(key) and words in str(ei.value) and str(p) in str(ei.value), str(ei.value)


def test_reader_lists_every_schema_problem_at_once(tmp_path, comp):
    """The reader checks the shipped schema first: three problems, one error naming all three."""
    p = _bad(tmp_path, comp, lambda d: d.update(method="fem", mass_kg=-1, tool_mm=[1, 2]))
    with pytest.raises(ComplianceError) as ei:
        read_compliance(p)
    msg = str(ei.value)
    assert "'fem'" in msg and "got -1" in msg and "key `tool_mm`" in msg and ei.value.line is not None


def test_reader_json_syntax_line(tmp_path, comp):
    p = _bad(tmp_path, comp, lambda d: None, text='{\n "format": "rodlab.compliance/1",\n "rod": \n}')
    with pytest.raises(ComplianceError) as ei:
        read_compliance(p)
    assert ei.value.line == 4 and "JSON" in str(ei.value)
    with pytest.raises(ComplianceError, match="not found"):
        read_compliance(tmp_path / "missing.json")
    q = tmp_path / "list.json"
    q.write_text("[1, 2]")
    with pytest.raises(ComplianceError, match="object"):
        read_compliance(q)


def test_writer_refuses_nan(tmp_path, comp):
    with pytest.raises(ValueError):
        RodCompliance(comp.rod, Method.CALC, comp.C_F * np.nan, comp.C_g, 1.0, np.zeros(3), np.zeros(3))
