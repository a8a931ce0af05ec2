"""Compliance files: round trip, contract example, Eq. 21/23, and every reader check."""
from __future__ import annotations

import json

import numpy as np
import pytest

from rodlab import ComplianceError, Method, RodCompliance, c_rod_um, load_design, r_rod, read_compliance, \
    write_compliance
from rodlab.core.calc import calc_rod_compliance

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


def _measured(comp) -> RodCompliance:
    """A measured-looking file: r_mn on the measured entries only (column y and z: loads along y and z)."""
    from dataclasses import replace
    from rodlab.core.compliance import r_mn
    meas = np.full((3, 3), np.nan)
    meas[:, 1:] = comp.C_F[:, 1:] * 1.07
    sigma = np.where(np.isfinite(meas), 2e-4, np.nan)
    return replace(comp, method=Method.MEAS, r_mn=r_mn(meas, comp.C_F), C_F_sigma=sigma)


def test_v2_round_trip_keeps_nulls(tmp_path, comp):
    """r_mn and C_F_sigma survive a write / read with null where not measured; the file states /2 and passes
    its schema; a file without them stays /1."""
    from rodlab.core.schema import check_file
    m = _measured(comp)
    p = write_compliance(m, tmp_path / "m.compliance.json")
    data = json.loads(p.read_text())
    assert data["format"] == "rodlab.compliance/2"
    assert data["r_mn"][0][0] is None and data["C_F_sigma_mm_per_N"][1][0] is None
    assert check_file(p).ok
    back = read_compliance(p)
    # r_mn of an entry whose simulated value is ~0 (C_F[0,1] of a planar rod) is null too
    expect = np.where(np.abs(comp.C_F) > 1e-9 * np.abs(comp.C_F).max(), 1.07, np.nan)
    expect[:, 0] = np.nan
    np.testing.assert_allclose(back.r_mn, expect, rtol=1e-9)
    np.testing.assert_array_equal(np.isnan(back.C_F_sigma), np.isnan(m.C_F_sigma))
    plain = json.loads(write_compliance(comp, tmp_path / "c.compliance.json").read_text())
    assert plain["format"] == "rodlab.compliance/1" and "r_mn" not in plain


V2_CASES = [
    ("v2 key in a v1 file", lambda d: d.update(format="rodlab.compliance/1"), "r_mn", "rodlab.compliance/2"),
    ("r_mn shape", lambda d: d.update(r_mn=[[1, None], [1, 1]]), "r_mn", "3 items"),
    ("r_mn text", lambda d: d["r_mn"][1].__setitem__(1, "x"), "r_mn", "a number or a null"),
    ("sigma negative", lambda d: d["C_F_sigma_mm_per_N"][1].__setitem__(1, -1e-3), "C_F_sigma_mm_per_N", "outside"),
]


@pytest.mark.parametrize("label,mutate,key,words", V2_CASES, ids=[c[0] for c in V2_CASES])
def test_v2_reader_rejects(tmp_path, comp, label, mutate, key, words):
    p = _bad(tmp_path, _measured(comp), mutate)
    with pytest.raises(ComplianceError) as ei:
        read_compliance(p)
    assert ei.value.key.startswith(key) and words in str(ei.value) and str(p) in str(ei.value), str(ei.value)


def test_the_design_file_is_found_from_any_working_folder(tmp_path, monkeypatch):
    """The provenance keeps the design file's absolute path: a diagnosis run from another folder still finds the
    design's tolerances (with the path as typed it fell back to a generic envelope)."""
    from rodlab import calc_rod_compliance, load_design
    from rodlab.app.diagnose.envelope import design_of
    from conftest import legacy_file
    (tmp_path / "a").mkdir()
    legacy_file(tmp_path / "a" / "my.rod.toml", "rod1")
    monkeypatch.chdir(tmp_path / "a")
    comp = calc_rod_compliance(load_design("my.rod.toml"))
    assert comp.provenance["design_file"] == str((tmp_path / "a" / "my.rod.toml").resolve())
    monkeypatch.chdir(tmp_path)
    assert design_of(comp) is not None
