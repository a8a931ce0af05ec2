"""Calibration of the campaign diagnosis's even-spread test (rodlab/app/diagnose/spread.py): how often it calls
evenly spread noise "at a position" on simulated null campaigns, the device noise true / stated = FACTOR; and how
often the time test (a trend within the positions) calls it "changing with time".

    python benchmarks/spread_null.py [N] [FACTOR]     # N seeds from 1000 (default 600, 2.0); about 4 min for 600

It applies the test to the identified campaign's residuals directly (the diagnosis applies it only when the
residual test fails, which at FACTOR 1 it rarely does). Results: docs/diagnose.md.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from rodlab import calc_rod_compliance, resolve_design
from rodlab.app.diagnose import campaign as C
from rodlab.app.diagnose.campaign_excess import time_trend_test
from rodlab.app.diagnose.spread import position_share_test
from rodlab.calibrate import (campaign_observations, FitOptions, identify, read_campaign, read_fixture,
                              resolve_robot, Rod, RodDeflection)
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign


def p_even(robot, rod, seed: int, factor: float) -> tuple[float, float]:
    """The tests' p (even spread, time) on one null campaign whose device noise is ``factor`` times the stated
    3 um."""
    with tempfile.TemporaryDirectory() as tmp:
        simulate_campaign(robot, rod, tmp, CampaignSpec(seed=seed, device_noise_mm=0.003 * factor,
                                                        validation_points=5))
        camp = read_campaign(Path(tmp) / "multical.campaign.csv")
        obs = campaign_observations(camp, read_fixture(Path(tmp) / "multical.fixture.json"), rod)
    res = identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod)],
                   FitOptions(expected_noise_mm=0.003, fixture_sigma=(0.01, 0.002)))
    ctx, tau = C.campaign_context(robot, res, obs, camp, rod)
    sel = C.CampaignSelection(ctx, tau, 0.003, (0.01, 0.002), 3)
    ew = sel.fit([])[2]
    _, null_cov = C.device_noise_null(sel, ew, sel.J)
    return (position_share_test(ew, sel.J, np.asarray(camp.position), np.ones(sel.N, bool), null_cov).p,
            time_trend_test(sel, ew, sel.J, camp))


def main() -> int:
    n = int(sys.argv[1]) if len(sys.argv) > 1 else 600
    factor = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    robot, rod = resolve_robot("tx90"), calc_rod_compliance(resolve_design("rod1"))
    p, pt = np.array([p_even(robot, rod, 1000 + s, factor) for s in range(n)]).T
    print(f"device noise {factor:g}x stated, {n} null campaigns: p <= 0.01 in {np.mean(p <= 0.01):.1%}, "
          f"p <= 0.05 in {np.mean(p <= 0.05):.1%}, p <= 0.5 in {np.mean(p <= 0.5):.1%}; time test p <= 0.01 in "
          f"{np.mean(pt <= 0.01):.1%}, p <= 0.05 in {np.mean(pt <= 0.05):.1%}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
