"""Creep of two terms (a fast one of seconds and a slow one of tens of seconds): the simulator makes it
(``creep:phi_2=..,tau_2_s=..``), the diagnosis told the simulation is exact names it as one creep with both
terms, where one creep term had left the fast one to a uniform scale; a true scale beside a one-term creep stays
that. The closed-form creep columns equal the reading-by-reading recursion."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.app.cli import main
from rodlab.app.diagnose import diagnose_rig
from rodlab.core.compliance import read_compliance
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.effects.creep import kelvin_voigt


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    folder = tmp_path_factory.mktemp("creep2")
    assert main(["fea", "rod1", "--model", "calc", "-o", str(folder / "rod1.compliance.json")]) == 0
    return folder


def _diagnosed(sim, name, *effects):
    rec = sim / f"{name}.rig.csv"
    args = ["rig", "simulate", "--sim", str(sim / "rod1.compliance.json"), "--hold-s", "30", "--repeats", "3",
            "-o", str(rec)]
    for e in effects:
        args += ["--effect", e]
    assert main(args) == 0
    diag, _ = diagnose_rig(read_recording(rec), read_compliance(sim / "rod1.compliance.json"), None, accuracy="exact")
    return {f.effect.value: f.parameters for f in diag.findings}


def test_two_creep_terms_are_one_creep_with_both(sim):
    found = _diagnosed(sim, "two", "creep:phi=0.015,tau_s=40,phi_2=0.02,tau_2_s=3")
    assert set(found) == {"creep"}
    p = found["creep"]
    (phi_slow, tau_slow), (phi_fast, tau_fast) = sorted([(p["phi"], p["tau_s"]), (p["phi_2"], p["tau_2_s"])],
                                                        key=lambda v: -v[1])
    assert phi_slow == pytest.approx(0.015, rel=0.1) and tau_slow == pytest.approx(40, rel=0.15)
    assert phi_fast == pytest.approx(0.02, rel=0.1) and tau_fast == pytest.approx(3, rel=0.25)


def test_a_scale_beside_one_creep_term_stays_a_scale(sim):
    found = _diagnosed(sim, "scale", "creep:phi=0.015,tau_s=40", "compliance_scale:r=1.03")
    assert set(found) == {"creep", "compliance_scale"} and "phi_2" not in found["creep"]
    assert found["compliance_scale"]["r"] == pytest.approx(1.03, abs=0.003)


def test_creep_columns_in_closed_form_equal_the_recursion():
    rng = np.random.default_rng(1)
    n = 3000
    data = type("Samples", (), {})()
    data.t_abs = np.cumsum(rng.uniform(0.05, 2.0, n))        # ~3000 s: several blocks at tau 0.3 s
    data.zero_groups = np.repeat([0, 1], [1200, 1800])
    base = rng.normal(size=n)
    taus = np.array([0.3, 3.0, 40.0, 1e4])
    want = np.zeros((n, taus.size))
    for g in (0, 1):
        idx = np.nonzero(data.zero_groups == g)[0]
        x = np.zeros(taus.size)
        for i, row in enumerate(idx):
            dt = 0.0 if i == 0 else data.t_abs[row] - data.t_abs[idx[i - 1]]
            keep = np.exp(-dt / taus)
            x = x * keep + (1 - keep) * base[row]
            want[row] = x
    assert np.allclose(kelvin_voigt(data, base, taus), want, rtol=0, atol=1e-10)
