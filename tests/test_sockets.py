"""Ball-in-socket and ball-bar calibration: known-truth recovery jointly across placements, the scale that only
a known distance gives, the reader's errors, and the command on public real data (MUKCa)."""
from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rodlab.calibrate import CalibrationError, ModelParams, read_robot, resolve_robot
from rodlab.calibrate.simulate import random_truth
from rodlab.calibrate.simulate_sockets import SocketSpec, simulate_sockets
from rodlab.calibrate.socket_check import check_sockets
from rodlab.calibrate.socket_fit import identify_sockets, socket_start
from rodlab.calibrate.sockets import read_sockets, write_sockets
from rodlab.app.cli.main import main

DATA = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "mukca2025"
TOOL = np.array([0.0, 0.0, 150.0])


@pytest.fixture(scope="module")
def tx90():
    return resolve_robot("tx90")


@pytest.fixture(scope="module")
def truth(tx90):
    return random_truth(tx90, TOOL, np.random.default_rng(3))


def _true_value(robot, truth: ModelParams, info) -> float:
    """The truth of one catalogue parameter in contract units (as the result states it)."""
    i, k = info.index, info.kind
    return {"dtheta": lambda: np.rad2deg(truth.theta_offset[i]) - robot.theta_offset_deg[i],
            "d": lambda: truth.d[i], "a": lambda: truth.a[i], "alpha": lambda: np.rad2deg(truth.alpha[i]),
            "beta": lambda: np.rad2deg(truth.beta[i]), "c": lambda: truth.c[i],
            "tool": lambda: truth.tool["xyz".index(info.name[-1])]}[k]()


@pytest.mark.parametrize("bar_mm", [0.0, 150.0], ids=["seats", "ball bar"])
def test_known_truth_is_recovered_and_generalises_to_unseen_placements(tx90, truth, bar_mm):
    spec = SocketSpec(placements=5, readings=15, bar_mm=bar_mm)
    fit = identify_sockets(tx90, simulate_sockets(tx90, truth, spec, seed=1), fix_unidentifiable=True)
    res = fit.result
    assert res.success and not res.warnings, res.warnings
    assert not res.residual_check.missing
    # every identified parameter of joints 1-4 within 5 standard errors of the truth (the standard errors are
    # honest); the wrist's and the tool's absorb the held a_5, d_5 and the last row (combinations)
    z = {i.name: (res.values[i.name] - _true_value(tx90, truth, i)) / res.sigma[i.name]
         for i in res.infos if res.status[i.name] == "identified" and i.kind not in ("c", "tool") and i.index < 4}
    assert len(z) >= 12 and max(abs(v) for v in z.values()) < 5, z
    rms_z = float(np.sqrt(np.mean(np.square(list(z.values())))))
    assert 0.3 < rms_z < 2.5, rms_z          # neither inflated (e.g. mrad stated as deg) nor too small
    # on placements the fit never saw, the calibrated model is as consistent as the truth itself
    test = simulate_sockets(tx90, truth, replace(spec, placements=3), seed=2)
    nominal, calibrated, perfect = (check_sockets(tx90, p, test) for p in
                                    (socket_start(tx90, test), res.params, truth))
    assert nominal.spread_rms_mm > 20 * calibrated.spread_rms_mm
    assert calibrated.spread_rms_mm < perfect.spread_rms_mm + 2 * (0.02 if bar_mm else 0.004) + 0.005
    assert calibrated.distance_rms_mm < 0.03 and nominal.distance_rms_mm > 0.1


def test_without_a_known_distance_the_scale_is_held_and_named(tx90, truth):
    r = simulate_sockets(tx90, truth, SocketSpec(placements=4, readings=12), seed=4)
    held = identify_sockets(tx90, replace(r, distances=()), fix_unidentifiable=True).result
    with_distance = identify_sockets(tx90, r, fix_unidentifiable=True).result
    lost = set(with_distance.free) - set(held.free)
    assert len(lost) == 1 and len(held.free) == len(with_distance.free) - 1     # one length: the overall scale
    (name,) = lost
    assert name.startswith(("a_", "d_")), name
    assert any(u.startswith(f"{name} (held: it sets the overall scale") for u in held.unidentifiable)
    # a ball bar's lengths fix the scale themselves
    bar = simulate_sockets(tx90, truth, SocketSpec(placements=3, readings=12, bar_mm=150.0), seed=4)
    free = identify_sockets(tx90, replace(bar, distances=()), fix_unidentifiable=True).result
    assert not any("overall scale" in u for u in free.unidentifiable)


def test_base_is_the_frame_of_the_centres_not_a_parameter(tx90, truth):
    """Pinning the base elsewhere moves every centre with it and leaves the robot's parameters as they were."""
    r = simulate_sockets(tx90, truth, SocketSpec(placements=3, readings=12), seed=5)
    a = identify_sockets(tx90, r, fix_unidentifiable=True)
    b = identify_sockets(tx90, r, fix_unidentifiable=True, pinned={"base_x": 5.0, "base_z": -3.0})
    assert all(a.result.status[f"base_{k}"] == "fixed" for k in "xyzabc")
    shift = np.array([b.centres_mm[g] - a.centres_mm[g] for g in a.centres_mm])
    assert np.allclose(shift, [5.0, 0.0, -3.0], atol=1e-4)
    for nm in a.result.free:
        assert abs(a.result.values[nm] - b.result.values[nm]) < 1e-4 * max(1.0, a.result.sigma[nm] * 1e3), nm


@pytest.mark.skipif(not (DATA / "panda_7.sockets.csv").exists(), reason="MUKCa data not converted")
def test_without_a_distance_real_data_keep_their_scale():
    """Real readings start far from the truth (mm of error): without a known distance the fit would shrink the
    robot; the longest row is held for the scale and the unseen placement's 50 mm stays 50 mm."""
    robot = read_robot(DATA / "panda.urdf", tip_link="ball_link")
    r = read_sockets(DATA / "panda_7.sockets.csv", robot.n)
    fit = identify_sockets(robot, replace(r.subset([1]), distances=()), fix_unidentifiable=True)
    assert any("sets the overall scale" in u for u in fit.result.unidentifiable)
    assert check_sockets(robot, fit.result.params, r.subset([2])).distance_rms_mm < 0.3


def test_ordinary_comments_are_kept_out_of_the_keys(tmp_path, tx90, truth):
    r = simulate_sockets(tx90, truth, SocketSpec(placements=2, readings=6), seed=8)
    back = read_sockets(write_sockets(tmp_path / "c.sockets.csv", r, "Source: https://example.org\nRobot: tx90"),
                        tx90.n)
    assert back.distances == r.distances


def test_file_round_trip(tmp_path, tx90, truth):
    for bar in (0.0, 120.0):
        r = simulate_sockets(tx90, truth, SocketSpec(placements=2, readings=6, bar_mm=bar), seed=6)
        back = read_sockets(write_sockets(tmp_path / "r.sockets.csv", r, "simulated"), tx90.n)
        assert np.allclose(back.q_rad, r.q_rad, atol=1e-8) and np.array_equal(back.placement, r.placement)
        assert back.distances == r.distances and back.ball_bar == (bar > 0)
        if bar:
            assert np.allclose(back.length_mm, r.length_mm, atol=1e-6)


BAD = [
    ("# distanse_mm: 1-2 = 50\n", "unknown key 'distanse_mm'; did you mean 'distance_mm'", 1),
    ("# distance_mm: 1-1 = 50\n", "two different socket numbers", 1),
    ("# distance_mm: 1-3 = 50\n", "names socket\\(s\\) \\[3\\]", None),
    ("# seat_sigma_mm: -1\n", "standard deviation > 0", 1),
    ("# tool_mm: 0, 0\n", "3 finite numbers", 1),
]


@pytest.mark.parametrize("head,message,line", BAD)
def test_reader_names_the_problem(tmp_path, head, message, line):
    rows = "\n".join(f"1,{s},{','.join(str(10 * s + k) for k in range(6))}" for s in (1, 2) for _ in range(3))
    path = tmp_path / "bad.sockets.csv"
    path.write_text(head + "placement,socket,q1,q2,q3,q4,q5,q6\n" + rows + "\n")
    with pytest.raises(CalibrationError, match=message) as e:
        read_sockets(path, 6)
    assert e.value.path is not None and (line is None or e.value.line == line)


def test_reader_refuses_a_socket_too_few_readings_locate(tmp_path):
    path = tmp_path / "few.sockets.csv"
    path.write_text("placement,socket,q1,q2,q3,q4,q5,q6\n1,1,0,0,0,0,0,0\n1,1,1,0,0,0,0,0\n1,2,0,1,0,0,0,0\n")
    with pytest.raises(CalibrationError, match="placement 1, socket 2 has 1 reading") as e:
        read_sockets(path, 6)
    assert e.value.line == 4


@pytest.mark.skipif(not (DATA / "panda_7.sockets.csv").exists(), reason="MUKCa data not converted")
def test_real_panda_data_matches_the_sources_own_calibration(tmp_path, capsys):
    """MUKCa's Panda 7: fitted on the front placement, checked on the right one. The command's verdict follows
    the held-out placements (usable: far better than nominal), with the stated seat play's completeness caution;
    its held-out consistency equals that of the source's own calibrated URDF."""
    args = ["calibrate", "--sockets", str(DATA / "panda_7.sockets.csv"), "--robot", str(DATA / "panda.urdf"),
            "--tip-link", "ball_link", "--fix-unidentifiable", "--fit-placements", "1"]
    assert main(args + ["--json", str(tmp_path / "cal.json"), "--report"]) == 0    # 50 um stated, ~200 um seen
    html = (tmp_path / "calibrate.report.html").read_text()
    assert "Consistency and distortion" in html and "held out" in html
    io = capsys.readouterr()
    assert "seat 50.0 um per coordinate" in io.out and "the model is incomplete" in io.err
    assert "usable? yes" in io.out and "complete? no" in io.out
    data = json.loads((tmp_path / "cal.json").read_text())
    held = data["sockets"]["checks"]["held out"]
    assert held["calibrated"]["spread_mean_mm"] < held["nominal"]["spread_mean_mm"] / 10
    theirs = read_robot(DATA / "panda_7_mukca_calibrated.urdf", tip_link="ball_link")
    test = read_sockets(DATA / "panda_7.sockets.csv", 7).subset([2])
    assert abs(check_sockets(theirs, socket_start(theirs, test), test).spread_mm.mean()
               - held["calibrated"]["spread_mean_mm"]) < 0.02
    assert main(args + ["--noise-um", "300"]) == 0                              # the play the data show
    assert main(["validate", str(DATA / "panda_7.sockets.csv")]) == 0


@pytest.mark.skipif(not (DATA / "dinova_2.sockets.csv").exists(), reason="MUKCa data not converted")
def test_real_kinova_with_backlash_nothing_unseen_is_fitted():
    """MUKCa's Kinova Gen3 lite (joints with backlash, axes 2 and 3 2e-4 deg from parallel in its URDF): the
    rows are sane, compliances of joints with almost no torque are held with the reason (they ran off to
    554 rad/(N m) with a zero sigma before), every fitted sigma is finite, the unconstrained fit's joint-2
    parameters leave their physical range (not trusted as they stand; the CLI holds them: tests/test_verdict_realdata.py)
    and the model still improves on placements it never saw."""
    robot = read_robot(DATA / "gen3lite.urdf", tip_link="ball_link")
    assert np.abs(robot.d_mm).max() < 500 and robot.parallel_rows() == [1]
    readings = read_sockets(DATA / "dinova_2.sockets.csv", robot.n)
    res = identify_sockets(robot, readings.subset([1, 3]), fix_unidentifiable=True).result
    held = [u for u in res.unidentifiable if u.startswith("c_6") or u.startswith("c_5")]
    assert len(held) == 2 and all("too little effect" in u for u in held)
    assert all(np.isfinite(res.sigma[n]) and res.sigma[n] > 0 for n in res.free)
    assert res.warnings and res.residual_check.p_value < 1e-6
    test = readings.subset([2, 4])
    assert check_sockets(robot, res.params, test).spread_mm.mean() < \
        0.8 * check_sockets(robot, socket_start(robot, test), test).spread_mm.mean()
