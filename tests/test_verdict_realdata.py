"""The calibration verdict as two statements on real and simulated data: usable? (held-out accuracy against the
nominal model, plausibility, degrees of freedom, overfitting) decides the exit code; complete? (the residual
test) is a caution. Real tracker data with default options are trusted when they predict better; the wrong
robot file and too few poses are not; parameters the data cannot separate are held at nominal by default."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli.main import main
from rodlab.calibrate import Observations, resolve_robot
from rodlab.calibrate.crossval import Prediction, fold_labels
from rodlab.calibrate.trust import prediction_warnings
from rodlab.core.enums import AccuracySource

DATA = Path(__file__).resolve().parents[1] / "benchmarks" / "data"


def _head_and_rows(path: Path) -> tuple[list, list]:
    lines = path.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [next(ln for ln in lines if ln.startswith("q1"))]
    return head, [ln for ln in lines if ln and not ln.startswith(("#", "q1"))]


@pytest.fixture(scope="module")
def ur5_quarter(tmp_path_factory) -> Path:
    """Every fourth grid pose of the public UR5 tracker data (250 poses)."""
    head, rows = _head_and_rows(DATA / "jacobi2025" / "ur5_grid.validation.csv")
    path = tmp_path_factory.mktemp("ur5") / "ur5.validation.csv"
    path.write_text("\n".join(head + rows[::4]) + "\n")
    return path


def test_real_fanuc_sweeps_are_trusted_along_the_sweeps_with_that_caution(tmp_path, capsys):
    """FANUC N1 -> N2 as a new user runs it: N2 measures N1's joint configurations with another reflector, so the
    verdict comes from cross-validation; the poses are single-joint sweeps about one configuration, so the
    held-out accuracy holds along them only, a caution (a trial's fit of the source's 36-pose recording, trusted at
    0.22 mm, missed this 59-pose recording of the same robot by 1.17 mm; holding out whole sweeps instead had
    predicted honest simulated sweeps worse than nominal, review). Trusted (exit 0) with that caution and its
    completeness caution; the unidentifiable parameters held with their reason; a periodic error named, not
    advised."""
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--points", str(DATA / "boby2021" / "r2000ic_N1.validation.csv"), "--robot",
                 "r2000ic165f", "--validate", str(DATA / "boby2021" / "r2000ic_N2.validation.csv"),
                 "--json", str(out)]) == 0
    io = capsys.readouterr()
    assert "usable? yes" in io.out and "complete? no" in io.out and "verdict: TRUSTED" in io.out
    assert "cross-validation over interleaved poses of one-joint sweeps" in io.out and "held at nominal" in io.out
    assert "caution (trusted): the poses turn one joint at a time" in io.err and "NOT TRUSTED" not in io.err
    cal = json.loads(out.read_text())
    pred = cal["fit"]["prediction"]
    assert cal["trusted"] and pred["source"] == "cross_validation" and pred["clearly_better"]
    assert pred["grouping"] == "interleaved poses of one-joint sweeps"
    assert any("one joint at a time" in c for c in cal["fit"]["cautions"])
    assert cal["fit"]["completeness"]["verdict"] == "incomplete"
    held = {u.split(" ")[0] for u in cal["unidentifiable"] if "in this data set" in u}
    assert {"d_3", "c_3"} <= held
    periodic = [ln for ln in io.out.splitlines() + io.err.splitlines() if "periodic_joint_error (joint" in ln]
    assert periodic and all("seen in joint" in ln and "--joint-harmonics 1" not in ln for ln in periodic)  # named


def test_sweeps_are_found_in_one_joint_at_a_time_poses_only():
    """joint_sweeps: six sweeps of six poses about a home pose (the return steps moving two joints) are six
    sweeps; random poses and a grid moving every joint are none."""
    from rodlab.calibrate.crossval import joint_sweeps
    home = np.radians([0.0, -30.0, 20.0, 0.0, -45.0, 10.0])
    rows = []
    for j in range(6):
        for a in np.linspace(-30.0, 30.0, 6):
            q = home.copy()
            q[j] += np.radians(a)
            rows.append(q)
    labels = joint_sweeps(np.array(rows))
    assert labels is not None and labels.tolist() == [j for j in range(6) for _ in range(6)]
    rng = np.random.default_rng(1)
    assert joint_sweeps(rng.uniform(-3, 3, (40, 6))) is None
    serpentine = []                                       # two joints, row after row (review: had been 'sweeps')
    for i, a in enumerate(np.linspace(-40.0, 40.0, 6)):
        for b in np.linspace(-30.0, 30.0, 6)[::(-1 if i % 2 else 1)]:
            serpentine.append(np.radians([0.0, a, b, 0.0, 30.0, 0.0]))
    assert joint_sweeps(np.array(serpentine)) is None


def test_strict_refuses_what_the_data_cannot_identify(capsys):
    assert main(["calibrate", "--points", str(DATA / "boby2021" / "r2000ic_N1.validation.csv"), "--robot",
                 "r2000ic165f", "--strict"]) == 2
    err = capsys.readouterr().err
    assert "cannot identify" in err and "d_3" in err


def test_the_wrong_robot_file_is_not_trusted(ur5_quarter, capsys):
    """UR5 data calibrated as a UR10: it fits and even predicts the random poses well, but the link lengths move
    by ~180 mm, beyond any manufacturing error: NOT TRUSTED, exit 3."""
    assert main(["calibrate", "--points", str(ur5_quarter), "--robot", "ur10", "--validate",
                 str(DATA / "jacobi2025" / "ur5_random.validation.csv")]) == 3
    err = capsys.readouterr().err
    assert "NOT TRUSTED" in err and "a_2 moved" in err and "not a plausible manufacturing error" in err


def test_too_few_poses_are_not_trusted(tmp_path, capsys):
    """The first 12 grid poses (36 readings for 26 parameters): too few degrees of freedom, and the
    cross-validated error is many times the fit's: NOT TRUSTED, exit 3, with and without a validation file."""
    head, rows = _head_and_rows(DATA / "jacobi2025" / "ur5_grid.validation.csv")
    path = tmp_path / "few.validation.csv"
    path.write_text("\n".join(head + rows[:12]) + "\n")
    assert main(["calibrate", "--points", str(path), "--robot", "ur5", "--json", str(tmp_path / "c.json")]) == 3
    err = capsys.readouterr().err
    assert "NOT TRUSTED" in err and "degrees of freedom" in err and "overfitting" in err
    cal = json.loads((tmp_path / "c.json").read_text())
    assert not cal["trusted"] and cal["fit"]["prediction"]["source"] == "cross_validation"
    assert cal["fit"]["prediction"]["overfit_ratio"] > 3
    assert main(["calibrate", "--points", str(path), "--robot", "ur5", "--validate",
                 str(DATA / "jacobi2025" / "ur5_random.validation.csv")]) == 3


def test_cross_validation_of_complete_simulated_points_predicts_the_noise(tmp_path):
    """Tracker points of a known truth with 25 um noise per coordinate and nothing the model leaves out: the
    cross-validated error per coordinate is the noise (slightly above: each fold fits fewer points), far below
    the nominal model's, and the prediction passes; the model is complete."""
    from test_points_workflow import _write_points

    from rodlab.calibrate import read_points
    from rodlab.calibrate.points import cross_validate_points, identify_points
    robot = resolve_robot("r2000ic165f")
    pts = read_points(_write_points(tmp_path / "p.validation.csv", robot, seed=11, n=150), robot.n)
    res = identify_points(robot, pts, 0.025, fix_unidentifiable=True)
    pred = cross_validate_points(robot, pts, res.rms_mm)
    assert pred.source is AccuracySource.CROSS_VALIDATION and pred.folds == 5 and pred.points == 150
    assert 0.025 < pred.rms_per_coordinate_mm < 0.025 * 1.4
    assert pred.nominal_mean_mm > 5 * pred.mean_mm and pred.clearly_better() and not prediction_warnings(pred)
    assert 0.9 < pred.overfit_ratio < 1.5 and not res.residual_check.missing


def test_folds_follow_clamping_positions_else_interleave_the_poses():
    q, x = np.zeros((12, 6)), np.zeros((12, 3))
    group = np.repeat([1, 2, 3, 4], 3)
    labels, how = fold_labels(Observations(q, x, x, group=group), k=5)
    assert how == "clamping positions" and len(set(labels)) == 4
    assert all(len(set(labels[group == g])) == 1 for g in range(1, 5))
    labels, how = fold_labels(Observations(q, x, x), k=5)
    assert how == "interleaved poses" and labels.tolist() == [i % 5 for i in range(12)]


def test_prediction_not_better_than_nominal_is_not_usable():
    """Paired held-out errors: a gain within 2 standard errors is not usable, a clear one is."""
    rng = np.random.default_rng(0)
    nominal = rng.uniform(0.4, 0.6, 40)
    same = Prediction.of_validation(nominal + rng.normal(0, 0.05, 40), nominal, 0.1)
    assert not same.clearly_better() and "does not predict clearly better" in prediction_warnings(same)[0]
    better = Prediction.of_validation(0.5 * nominal, nominal, 0.1)
    assert better.clearly_better() and not prediction_warnings(better)
    with pytest.raises(ValueError, match="paired"):
        Prediction.of_validation(np.zeros(3), np.zeros(4), 0.1)


MUKCA = DATA / "mukca2025"


@pytest.mark.skipif(not (MUKCA / "dinova_1.sockets.csv").exists(), reason="MUKCa data not converted")
@pytest.mark.parametrize("name, held", [("dinova_1", {"c_2"}), ("dinova_2", {"c_2", "dtheta_2"})])
def test_real_kinova_backlash_parameters_are_held_at_their_range_and_the_refit_is_trusted(tmp_path, capsys, name,
                                                                                         held):
    """The Gen3 lite's backlash drives joint 2's compliance (and on dinova_2 its offset) outside its physical
    range, by less than one standard uncertainty (c_2 = 1.9e-4 +- 3.6e-4 and -1.4e-4 +- 1.9e-4 rad/(N m)): the
    data cannot tell it from inside, so it is held at the range's end, refitted, and the refit predicts the
    held-out placements clearly better than nominal: trusted (exit 0) with the holds and the completeness caution
    in the output and the result file."""
    from rodlab.calibrate.plausible import RANGES
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--sockets", str(MUKCA / f"{name}.sockets.csv"), "--robot",
                 str(MUKCA / "gen3lite.urdf"), "--tip-link", "ball_link", "--fit-placements", "1,3",
                 "--json", str(out)]) == 0
    io = capsys.readouterr()
    assert "verdict: TRUSTED" in io.out and "NOT TRUSTED" not in io.err
    assert "the model is incomplete" in io.err and "end of its physical range" in io.err
    cal = json.loads(out.read_text())
    assert cal["trusted"] and cal["fit"]["prediction"]["clearly_better"]
    reasons = {u.split(" ")[0]: u for u in cal["unidentifiable"] if "end of its physical range" in u}
    assert set(reasons) == held
    for nm in held:
        p = cal["parameters"][nm]
        assert p["status"] == "fixed" and p["value"] in RANGES[nm.split("_")[0]]   # at an end of the range
        assert "cannot tell from inside the range" in reasons[nm]
    assert any(f"{nm} held at" in c for c in cal["fit"]["cautions"] for nm in held)


def test_a_significant_excursion_is_refused_an_insignificant_one_is_held():
    """The rule of calibrate.plausible on a stand-in fit: a compliance outside [0, 1e-4] by less than 3 of its
    standard uncertainties is held at the nearest end and the fit repeated with the pin; by more it is left for
    the refusal (trust_warnings) and nothing is refitted."""
    from types import SimpleNamespace

    from rodlab.calibrate.plausible import constrain_to_ranges
    from rodlab.calibrate.trust import trust_warnings
    info = SimpleNamespace(name="c_2", kind="c", unit="rad/(N m)", index=1)

    def fake(value, sigma):
        calls = []

        def fit(pins):
            calls.append(dict(pins))
            v = pins.get("c_2", value)
            return SimpleNamespace(infos=[info], values={"c_2": v}, sigma={"c_2": sigma},
                                   status={"c_2": "fixed" if "c_2" in pins else "identified"}, unidentifiable=[],
                                   cautions=[], success=True, message="", residuals_mm=np.zeros((50, 3)),
                                   free=[] if "c_2" in pins else ["c_2"], residual_check=None)
        return fit, calls

    fit, calls = fake(-1.4e-4, 1.9e-4)                 # 0.74 sigma below 0: held at 0
    res, pins = constrain_to_ranges(fit, {"d_1": 0.0})
    assert pins == {"d_1": 0.0, "c_2": 0.0} and len(calls) == 2 and res.values["c_2"] == 0.0
    assert "c_2 held at 0" in res.cautions[0] and res.unidentifiable[0].startswith("c_2 (held at 0")
    fit, calls = fake(3.0e-4, 0.5e-4)                  # 4 sigma above 1e-4: shown implausible, refused
    res, pins = constrain_to_ranges(fit)
    assert pins == {} and len(calls) == 1 and not res.cautions
    robot = resolve_robot("ur5")
    assert any("c_2" in w and "not a plausible gearbox compliance" in w for w in trust_warnings(robot, res))


@pytest.mark.skipif(not (MUKCA / "dinova_1.sockets.csv").exists(), reason="MUKCa data not converted")
def test_free_keeps_the_unconstrained_estimate_and_its_refusal(capsys):
    """--free c_2 asks for the unconstrained joint-2 compliance: no hold, and the range check judges it."""
    assert main(["calibrate", "--sockets", str(MUKCA / "dinova_1.sockets.csv"), "--robot", str(MUKCA / "gen3lite.urdf"),
                 "--tip-link", "ball_link", "--fit-placements", "1,3", "--free", "c_2"]) == 3
    err = capsys.readouterr().err
    assert "c_2 = 0.000192" in err and "not a plausible gearbox compliance" in err and "c_2 held at" not in err


@pytest.mark.skipif(not (MUKCA / "panda_6.sockets.csv").exists(), reason="MUKCa data not converted")
@pytest.mark.parametrize("name, urdf, fit_on", [("panda_6", "panda.urdf", "1"), ("panda_7", "panda.urdf", "1"),
                                                ("panda_2", "panda.urdf", "1,3,5,7,9"), ("panda_3", "panda.urdf", "1,3,5"),
                                                ("kuka_14", "iiwa14.urdf", "1,3")])
def test_real_panda_and_iiwa_sockets_are_trusted_without_holds(tmp_path, name, urdf, fit_on):
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--sockets", str(MUKCA / f"{name}.sockets.csv"), "--robot", str(MUKCA / urdf),
                 "--tip-link", "ball_link", "--fit-placements", fit_on, "--json", str(out)]) == 0
    cal = json.loads(out.read_text())
    assert cal["trusted"] and cal["fit"]["completeness"]["verdict"] == "incomplete"
    assert not any("end of its physical range" in u for u in cal["unidentifiable"])


def test_real_ur5_grid_to_random_is_trusted(tmp_path, capsys):
    """UR5 grid -> 20 random poses with default options: 0.428 -> 0.089 mm, trusted with its caution."""
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--points", str(DATA / "jacobi2025" / "ur5_grid.validation.csv"), "--robot", "ur5",
                 "--validate", str(DATA / "jacobi2025" / "ur5_random.validation.csv"), "--json", str(out)]) == 0
    pred = json.loads(out.read_text())["fit"]["prediction"]
    assert pred["mean_mm"] < 0.1 and pred["nominal_mean_mm"] > 0.4
    assert "caution (trusted): the model is incomplete" in capsys.readouterr().err


def test_real_ur10_b_to_c_is_trusted(tmp_path, capsys):
    """UR10 B -> C with default options: 0.901 -> 0.441 mm, trusted; the residual test says it weighs each point by
    the sigma it states (a trial: Birge 47 beside 238 / 17.6 um had read as a contradiction); its own moves from
    the robot file (<= 0.7 mm) are no caution."""
    d = DATA / "landgraf2021"
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--points", str(d / "ur10_B.validation.csv"), "--robot", "ur10", "--validate",
                 str(d / "ur10_C.validation.csv"), "--json", str(out)]) == 0
    pred = json.loads(out.read_text())["fit"]["prediction"]
    assert pred["mean_mm"] < 0.5 * pred["nominal_mean_mm"] and pred["clearly_better"]
    io = capsys.readouterr()
    assert "as each point states it" in io.out and "each point weighed by its own" in io.out
    assert "check those rows of the robot file" not in io.err


def test_a_validation_file_that_is_the_fit_is_no_held_out_test(capsys):
    """The FANUC's N1 points validated on themselves: said, and judged by cross-validation instead (the
    validation's errors are the fit's own)."""
    n1 = Path(__file__).resolve().parents[1] / "benchmarks" / "data" / "boby2021" / "r2000ic_N1.validation.csv"
    main(["calibrate", "--points", str(n1), "--robot", "r2000ic165f", "--validate", str(n1)])
    io = capsys.readouterr()
    assert "100% of its joint configurations are the fit's own" in io.err
    assert "by 5-fold cross-validation" in io.out


def test_a_joint_compliance_the_data_push_below_zero_is_said_and_a_pin_outside_its_range_refused(tmp_path, capsys):
    """The UR5 grid: c_3 is held at its bound 0 while the data, unbounded, put it ~9 sigma below it (a trial: with
    the measured-minus-target column's other sign c_2 went to 0 and c_3 to 41 urad/(N m), both fits trusted):
    said on stderr and in the JSON (at_bound, unconstrained_value). A pin outside [0, C_MAX] is refused, not
    clipped."""
    out = tmp_path / "cal.json"
    grid, rnd = DATA / "jacobi2025" / "ur5_grid.validation.csv", DATA / "jacobi2025" / "ur5_random.validation.csv"
    assert main(["calibrate", "--points", str(grid), "--robot", "ur5", "--validate", str(rnd), "--json",
                 str(out)]) == 0
    err = capsys.readouterr().err
    assert "warning: c_3 is held at 0; unbounded, the data put it at -" in err
    c3 = json.loads(out.read_text())["parameters"]["c_3"]
    assert c3["at_bound"] and c3["unconstrained_value"] < -3 * c3["sigma"] and abs(c3["value"]) < 1e-12
    for value, words in (("-3.2e-5", "sag of the wrong sign"), ("32", "32 urad/(N m) is 3.2e-05")):
        assert main(["calibrate", "--points", str(grid), "--robot", "ur5", "--pin", f"c_2={value}"]) == 2
        assert words in capsys.readouterr().err


#: a user's UR10 DH table typed by hand (a trial's), a_2 typed -607 for -612
UR10_A2_TYPO = """format = "rodlab.robot/2"
name = "my_ur10"
convention = "dh"
source = "Universal Robots UR10 (CB3) DH table from UR's support site, typed in by hand"
[[joint]]
limits_deg = [-360, 360]
name = "shoulder_pan"
d_mm = 127.3
a_mm = 0
alpha_deg = 90
mass_kg = 7.1
com_mm = [0, -25.6, 1.93]
[[joint]]
limits_deg = [-360, 360]
name = "shoulder_lift"
d_mm = 0
a_mm = -607
alpha_deg = 0
mass_kg = 12.7
com_mm = [306, 0, 175]
[[joint]]
limits_deg = [-360, 360]
name = "elbow"
d_mm = 0
a_mm = -572.3
alpha_deg = 0
mass_kg = 4.27
com_mm = [286, 0, 38]
[[joint]]
limits_deg = [-360, 360]
name = "wrist_1"
d_mm = 163.941
a_mm = 0
alpha_deg = 90
mass_kg = 2.0
com_mm = [0, -1.7, 10.8]
[[joint]]
limits_deg = [-360, 360]
name = "wrist_2"
d_mm = 115.7
a_mm = 0
alpha_deg = -90
mass_kg = 2.0
com_mm = [0, 1.7, 10.8]
[[joint]]
limits_deg = [-360, 360]
name = "wrist_3"
d_mm = 92.2
a_mm = 0
alpha_deg = 0
mass_kg = 0.365
com_mm = [0, 0, -1.2]
"""


def test_a_length_typed_off_in_the_robot_file_is_a_caution(tmp_path, capsys):
    """The UR10's a_2 typed 5 mm off: identified back and still trusted, with a caution naming it (a trial: no
    remark, the gain over 'nominal' inflated); the real sets' own moves (<= 0.7 mm, 0.7 deg) give none."""
    src = tmp_path / "my_ur10.toml"
    src.write_text(UR10_A2_TYPO)
    b, c = DATA / "landgraf2021" / "ur10_B.validation.csv", DATA / "landgraf2021" / "ur10_C.validation.csv"
    assert main(["calibrate", "--points", str(b), "--robot", str(src), "--validate", str(c)]) == 0
    err = capsys.readouterr().err
    assert "caution (trusted): a_2 -5." in err and "check those rows of the robot file" in err
    line = next(k for k, s in enumerate(UR10_A2_TYPO.splitlines(), start=1)
                if s.startswith("a_mm = -607"))                        # the typed row's own a_mm
    assert f"my_ur10.toml line {line})" in err


def test_real_wam_grid_is_predicted_by_blocks_not_by_its_interleaved_neighbours(tmp_path, capsys):
    """Public tracker data of a Barrett WAM (7 joints, cable-driven; benchmarks/data/jacobi2025): the 216 grid
    poses' interleaved folds keep every pose's grid neighbours in the fit and had predicted 2.17 mm; the source's
    20 random test poses measure 3.03 mm after the same calibration. The folds in blocks of the file are predicted
    too and the worse is stated: within 10 % of what the random poses measure, the interleaved one named beside it;
    on the random poses themselves the gain (0.54 +- 0.30 mm) is not clear: NOT TRUSTED, exit 3."""
    grid, test = (DATA / "jacobi2025" / f"wam_{n}.validation.csv" for n in ("grid", "random"))
    robot = str(DATA / "jacobi2025" / "wam7.toml")
    out = tmp_path / "cal.json"
    assert main(["calibrate", "--points", str(grid), "--robot", robot, "--json", str(out)]) == 0
    pred = json.loads(out.read_text())["fit"]["prediction"]
    assert pred["grouping"] == "blocks of poses in file order" and pred["other_split"].startswith("interleaved poses")
    printed = capsys.readouterr()
    # the tool length is well determined (sigma 0.46 mm): the first pass's scatter made it weak, the prior is
    # released once it is not (it had stayed `regularised`); the joint compliances are not identifiable here
    tool_z = next(line for line in printed.out.splitlines() if line.split()[:1] == ["tool_z"])
    assert tool_z.split()[-1] == "identified"
    assert "note: the joint compliances are not identifiable from these data" in printed.err
    assert main(["calibrate", "--points", str(grid), "--robot", robot, "--validate", str(test), "--json",
                 str(out)]) == 3
    measured = json.loads(out.read_text())["fit"]["prediction"]["mean_mm"]
    assert pred["mean_mm"] == pytest.approx(measured, rel=0.10)
    assert pred["other_split_mean_mm"] < 0.8 * measured                                   # the neighbours' optimism
