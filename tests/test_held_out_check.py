"""Findings and periodic terms checked on the validation points before they are advised: a term that fits the
campaign's poses but predicts other poses worse is said not to be applied (an IRB 4600 trial: a bending forearm
fitted as joint 3's periodic error, `--joint-harmonics 3` doubled the held-out error)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from rodlab.app.cli.cmd_calibrate import _harmonics_held_out
from rodlab.app.diagnose.campaign_holdout import HELD_OUT_WORSE, _judge
from rodlab.app.diagnose.report import Finding
from rodlab.calibrate.validate import clearly_worse

RNG = np.random.default_rng(5)
BASE = 0.05 + 0.01 * RNG.standard_normal(100)


@pytest.mark.parametrize("shift, noise, worse", [
    (0.02, 0.002, True),         # 20 um worse at every point: clearly
    (0.001, 0.0001, False),      # 1 um: below the 2 um floor however consistent
    (0.003, 0.05, False),        # 3 um on average within a scatter of 50 um: not shown
    (-0.02, 0.002, False),       # better
])
def test_clearly_worse_needs_a_consistent_and_material_difference(shift, noise, worse):
    with_mm = BASE + shift + noise * RNG.standard_normal(BASE.size)
    assert clearly_worse(with_mm, BASE) is worse


def test_a_finding_that_worsens_the_validation_is_cautioned():
    f = Finding("periodic_joint_error", "joint:3", "x", {}, {}, 0.013, 0.012, {"caution": "over part of a turn"})
    _judge(f, BASE + 0.03, BASE)
    assert f.evidence[HELD_OUT_WORSE] is True
    assert f.evidence["validation_mean_with_mm"] == pytest.approx(BASE.mean() + 0.03)
    assert "over part of a turn; the validation points are predicted worse with it" in f.evidence["caution"]
    assert "mm without it" in f.evidence["caution"]
    g = Finding("periodic_joint_error", "joint:4", "x", {}, {}, 0.013, 0.012, {})
    _judge(g, BASE - 0.01, BASE)
    assert g.evidence[HELD_OUT_WORSE] is False and "caution" not in g.evidence


def test_joint_harmonics_that_worsen_the_validation_make_the_result_untrusted():
    run = SimpleNamespace(calibrated_mm=BASE + 0.05, without_harmonics_mm=BASE)
    (why,) = _harmonics_held_out(run, (3,))
    assert "joint(s) 3 (--joint-harmonics) predict the validation points worse" in why
    assert f"{BASE.mean():.3f} mm without" in why and "calibrate without --joint-harmonics" in why
    assert _harmonics_held_out(SimpleNamespace(calibrated_mm=BASE - 0.01, without_harmonics_mm=BASE), (3,)) == []
    assert _harmonics_held_out(SimpleNamespace(calibrated_mm=BASE, without_harmonics_mm=None), (3,)) == []


def test_a_finding_the_validation_contradicts_is_advised_against():
    from rodlab.app.diagnose.advice import remedy
    f = Finding("periodic_joint_error", "joint:3", "x", {"amp_sin_rad": 1e-5, "amp_cos_rad": 1e-5}, {}, 0.013, 0.012,
                {})
    assert "--joint-harmonics" in remedy(f)
    _judge(f, BASE + 0.03, BASE)
    assert remedy(f).startswith("do not apply it to the robot") and "--joint-harmonics" not in remedy(f)
