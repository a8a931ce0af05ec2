"""A joint's zero that moved between clamping positions (re-homed, re-mastered, lost counts) is named as such,
at the shifted positions with its joint and size, not as wrong fixture poses and gross errors (an IRB 4600 trial:
two fixture poses and three outliers, and freeing those fixture keys worsened the held-out error)."""
from __future__ import annotations

import pytest

from conftest import diagnose_simulated, legacy_design
from rodlab import calc_rod_compliance
from rodlab.app.diagnose.advice import remedy
from rodlab.calibrate import resolve_robot
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign

ROBOT = resolve_robot("tx90")
ROD = calc_rod_compliance(legacy_design("rod1"))


def _diagnose(folder):
    return diagnose_simulated(folder, ROBOT, ROD)


def test_a_shift_over_two_positions_is_named_at_both_with_its_joint(tmp_path):
    """Joint 2 re-homed 0.008 deg off for positions 4 and 5 of 5: one finding per position, joint 2, the shift
    within 20 %, no fixture pose or outlier beside them, and the validation better with them."""
    simulate_campaign(ROBOT, ROD, tmp_path, CampaignSpec(seed=47), effects=[
        ("joint_zero_shift", {"position": 4, "joint": 2, "dtheta_deg": 0.008}),
        ("joint_zero_shift", {"position": 5, "joint": 2, "dtheta_deg": 0.008})])
    diag = _diagnose(tmp_path)
    found = sorted((f.effect.value, f.location) for f in diag.findings)
    assert found == [("joint_zero_shift", "position:4"), ("joint_zero_shift", "position:5")], diag.summary()
    for f in diag.findings:
        assert f.parameters["joint"] == 2
        assert f.parameters["dtheta_deg"] == pytest.approx(0.008, rel=0.2)
        assert "joint 2's zero at clamping position" in remedy(f) and "fixture pose is not the cause" in remedy(f)
    v = diag.extra["validation"]
    assert v["after"]["mean_mm"] < v["before"]["mean_mm"]


def test_a_wrong_fixture_pose_is_still_a_fixture_pose(tmp_path):
    """The rival at the same place: a clamping position's recorded pose 0.15 mm off is `fixture_pose`, not a shift
    of some joint (three parameters that fit against one that does not)."""
    simulate_campaign(ROBOT, ROD, tmp_path, CampaignSpec(seed=48),
                      effects={"fixture_pose": {"position": 3, "offset_mm": [0.12, -0.1, 0.06]}})
    diag = _diagnose(tmp_path)
    assert [(f.effect.value, f.location) for f in diag.findings] == [("fixture_pose", "position:3")], diag.summary()


@pytest.mark.parametrize("params, key", [({"position": 9, "joint": 2}, "joint_zero_shift.position"),
                                         ({"position": 2, "joint": 7}, "joint_zero_shift.joint")])
def test_a_shift_outside_the_campaign_or_the_robot_is_refused(tmp_path, params, key):
    with pytest.raises(CalibrationError) as e:
        simulate_campaign(ROBOT, ROD, tmp_path, CampaignSpec(seed=1), effects={"joint_zero_shift": params})
    assert e.value.key == key
    assert not list(tmp_path.iterdir())


def test_every_shift_keeps_its_margin_against_the_fixture_pose_at_its_place():
    """The search tries the next candidates when the first fails: a shift ranked second must still go behind the
    fixture pose of its position when that pose fits within the margin (a review found only the first deferred)."""
    from types import SimpleNamespace as NS

    from rodlab.app.diagnose.campaign_forms import DEFER_MARGIN, deferred

    def cand(effect, location, rss, defers_to=None):
        return NS(rss=rss, hyp=NS(effect=effect, location=location, defers_to=defers_to))
    outlier = cand("outliers", "points:2.3", 10.0)
    shift = cand("joint_zero_shift", "position:3", 20.0, "fixture_pose")
    other = cand("joint_zero_shift", "position:4", 21.0, "fixture_pose")
    fixture = cand("fixture_pose", "position:3", 20.0 + 0.5 * DEFER_MARGIN)
    assert deferred([outlier, shift, other, fixture]) == [outlier, fixture, shift, other]
    clear = cand("fixture_pose", "position:3", 20.0 + 2 * DEFER_MARGIN)      # the shift fits clearly better
    assert deferred([outlier, shift, other, clear]) == [outlier, shift, other, clear]
