"""Benchmark: identification of ~40 parameters from 150 points with compensation; analytic vs FD Jacobian.

    python benchmarks/bench_calibrate.py     # prints and writes docs/benchmarks/calibrate.md
Goal (issue: calibrate): <= 0.3 s on 2 cores.
"""
from __future__ import annotations

import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

from rodlab.calibrate import (campaign_observations, identify, read_campaign, read_fixture, resolve_robot, Rod,
                              RodDeflection)
from rodlab.calibrate.jacobian import position_jacobian
from rodlab.calibrate.kinematics import ball_positions
from rodlab.calibrate.params import apply
from rodlab.calibrate.simulate import CampaignSpec, simulate_campaign
from rodlab import calc_rod_compliance, resolve_design
from rodlab.core.fileio import atomic_write_text

OUT = Path(__file__).resolve().parents[1] / "docs" / "benchmarks" / "calibrate.md"


def main() -> int:
    robot = resolve_robot("tx90")
    rod = calc_rod_compliance(resolve_design("rod1"))
    with tempfile.TemporaryDirectory() as tmp:
        simulate_campaign(robot, rod, tmp, CampaignSpec(positions=5, orientations=30, seed=4, validation_points=10))
        camp, fix = read_campaign(Path(tmp) / "multical.campaign.csv"), read_fixture(Path(tmp) / "multical.fixture.json")
    obs = campaign_observations(camp, fix, rod)
    identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod)])
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        res = identify(robot, obs, Rod.of(rod), [RodDeflection.of(rod)])
        times.append(time.perf_counter() - t0)
    # analytic vs finite-difference Jacobian at the solution
    infos = [i for i in res.infos if i.name in res.free]
    x = np.zeros(len(infos))
    p = res.params
    t0 = time.perf_counter()
    for _ in range(20):
        fr, tau = ball_positions(robot, p, obs.q_rad, obs.rod, force_W_N=obs.force_W_N)
        position_jacobian(fr, tau, infos, p.base, obs.group)
    t_an = (time.perf_counter() - t0) / 20
    t0 = time.perf_counter()
    for _ in range(3):
        for k in range(len(infos)):
            e = np.zeros(len(infos))
            e[k] = 1e-6
            ball_positions(robot, apply(p, infos, x + e), obs.q_rad, obs.rod, force_W_N=obs.force_W_N)
    t_fd = (time.perf_counter() - t0) / 3
    lines = ["# Benchmark: calibration", "",
             f"`python benchmarks/bench_calibrate.py` on {platform.machine()}, {os.cpu_count()} cores, "
             f"{time.strftime('%Y-%m-%d')}.", "",
             f"- identification of {len(res.free)} parameters from {camp.n} points (5 positions x 30 orientations), "
             f"rod-deflection compensation included ({res.iterations} passes): median {np.median(times):.2f} s, "
             f"min {min(times):.2f} s (goal <= 0.3 s); fit rms {res.rms_mm * 1e3:.2f} um",
             f"- Jacobian: analytic {t_an * 1e3:.1f} ms vs forward differences {t_fd * 1e3:.0f} ms "
             f"({t_fd / t_an:.0f}x faster)", ""]
    atomic_write_text(OUT, "\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
