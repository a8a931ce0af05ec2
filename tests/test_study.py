"""rodlab study: the accuracy predictor's physics, the design physics beside it, Dask = serial, the command."""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from rodlab.calibrate import resolve_robot
from rodlab.calibrate.predict import Priors, predict_accuracy
from rodlab.calibrate.simulate import standard_base, standard_fixture
from rodlab.core.design_io import resolve_design
from rodlab.core.enums import Method


def test_perfect_files_leave_no_deflection_error(rod4_plan):
    """Files equal to the true rod (r = 1, no shape or measurement error): every compensating method gives the
    true-rod result, so the budget's deflection share vanishes, while no compensation keeps the deflection."""
    robot, fixture, plan, rod = rod4_plan
    pri = Priors(r_rod=(1.0, 1.0), shape_sigma=0.0, meas_sigma=0.0, validation_points=30)
    out = {a.method: a for a in predict_accuracy(robot, plan, fixture, standard_base(), rod, rod,
                                                 ["none", "fea", "meas"], pri, replicates=2, seed=3)}
    assert out[Method.FEA].budget.deflection < 1e-6
    assert out[Method.MEAS].mean_mm == pytest.approx(out[Method.FEA].mean_mm, rel=1e-9)
    assert out[Method.NONE].budget.deflection > 0.5
    assert out[Method.NONE].mean_mm > 2 * out[Method.FEA].mean_mm
    for a in out.values():
        parts = (a.budget.deflection, a.budget.identification, a.budget.noise)
        assert sum(parts) == pytest.approx(1.0) and min(parts) >= 0


def test_a_softer_rod_is_predicted_worse(rod4_plan):
    """Same draws, the same file errors (r in 1.2-1.3): a rod three times as compliant leaves three times the
    deflection after FEA compensation, so its predicted error is larger; the band contains the mean."""
    robot, fixture, plan, rod = rod4_plan
    pri = Priors(r_rod=(1.2, 1.3), validation_points=30)
    stiff = predict_accuracy(robot, plan, fixture, standard_base(), rod, None, ["fea"], pri, replicates=3, seed=1,
                             budget=False)[0]
    soft_rod = rod.scaled(3.0, Method.FEA)
    soft = predict_accuracy(robot, plan, fixture, standard_base(), soft_rod, None, ["fea"], pri, replicates=3,
                            seed=1, budget=False)[0]
    assert soft.mean_mm > 1.5 * stiff.mean_mm
    for a in (stiff, soft):
        assert a.mean_p05_mm <= a.mean_mm <= a.mean_p95_mm


def test_priors_are_checked():
    with pytest.raises(ValueError, match="r_rod"):
        Priors(r_rod=(1.5, 1.2))
    with pytest.raises(ValueError, match="device_noise_mm"):
        Priors(device_noise_mm=-1)


def test_uniform_expansion_scales_the_tool_vector():
    """Every part of the same CTE: the rod grows like a photograph, the ball moves by alpha * tool."""
    from rodlab.core.materials import Material
    from rodlab.core.strength import thermal_growth_um_per_K
    d = resolve_design("rod4")
    m = Material("same", 200.0, 0.3, 8000.0, cte_ppm_K=10.0)
    d = replace(d, pipe_I=replace(d.pipe_I, material=m), pipe_II=replace(d.pipe_II, material=m),
                bend=replace(d.bend, material=m), ball=replace(d.ball, material=m),
                ball_holder=replace(d.ball_holder, material=m), rings=replace(d.rings, material=m),
                pipe_holder=replace(d.pipe_holder, material=m))
    assert np.allclose(thermal_growth_um_per_K(d), 10.0 * np.asarray(d.tool_mm) * 1e-3, rtol=1e-9)


def test_cantilever_frequency_matches_euler_bernoulli():
    """A slender straight steel tube clamped at one end: f1 = 1.8751^2 / (2 pi) sqrt(EI / (m L^4))."""
    from rodlab.core.enums import Part
    from rodlab.fea.modal import chain_frequencies
    from rodlab.core.layout import Layer, Segment, SegmentKind
    from rodlab.core.materials import BUILTIN_MATERIALS
    steel = BUILTIN_MATERIALS["steel_304"]
    L = 1500.0
    seg = Segment(SegmentKind.LINE, 0.0, L, np.zeros(3), np.array([0.0, 0.0, 1.0]),
                  (Layer(Part.PIPE_I, steel, 20.0, 16.0),))
    f = chain_frequencies([seg], [0.0, 0.0, L], 0.0, [0.0, 0.0, L], modes=2, pieces=60)
    EI = seg.EI * 1e-6                                   # N mm^2 -> N m^2
    m = seg.mass_per_mm * 1e3                            # kg/m
    f1 = 1.8751 ** 2 / (2 * math.pi) * math.sqrt(EI / (m * (L * 1e-3) ** 4))
    assert f[0] == pytest.approx(f1, rel=5e-3)
    assert f[1] == pytest.approx(f1, rel=5e-3)           # the round tube bends alike in both planes


def test_strength_grows_with_the_contact_force():
    from rodlab.core.strength import strength_margins
    d = resolve_design("rod6")
    a, b = strength_margins(d, 2.0), strength_margins(d, 200.0)
    assert b.tube_stress_MPa > 10 * a.tube_stress_MPa and b.tube_margin < a.tube_margin
    assert b.bond_at in ("pipe_holder", "ring_1", "ring_2", "ball_holder plug")
    # a 200 N force at the ball bends pipe I at the holder by at most F * reach
    layer = d.pipe_I
    I = math.pi / 64 * (layer.outer_diameter_mm ** 4 - layer.inner_diameter_mm ** 4)
    bound = 200.0 * np.linalg.norm(d.tool_mm) * layer.outer_diameter_mm / 2 / I
    assert b.tube_stress_MPa < 1.5 * bound


def _candidates():
    from rodlab.app.study import grid_candidates
    base = resolve_design("rod4")
    return grid_candidates(base, [250.0, 300.0], [450.0])


@pytest.mark.parametrize("monte_carlo", [False, True])
def test_dask_cluster_gives_the_serial_results(tmp_path, monkeypatch, monte_carlo):
    pytest.importorskip("dask.distributed")
    from rodlab.app.study import StudySpec, run_study, study_table
    spec = StudySpec(methods=("none", "fea"), replicates=2, priors=Priors(validation_points=20), budget=False,
                     monte_carlo=monte_carlo, draws=64)
    import rodlab.app.study.run_fast as run_fast
    monkeypatch.setattr(run_fast, "DASK_MIN_DESIGNS", 1)      # the cluster even for these two designs
    robot, fixture = resolve_robot("tx90"), standard_fixture()
    serial = study_table(run_study(_candidates(), robot, fixture, spec, use_dask=False))
    dask = study_table(run_study(_candidates(), robot, fixture, spec, cache_dir=tmp_path / "c", workers=2))
    assert serial["mean_mm"].notna().all()
    np.testing.assert_allclose(dask["mean_mm"].to_numpy(float), serial["mean_mm"].to_numpy(float), rtol=1e-9)
    # resumed from the cache: nothing to compute, the same table
    again = study_table(run_study(_candidates(), robot, fixture, spec, cache_dir=tmp_path / "c", use_dask=False))
    np.testing.assert_allclose(again["mean_mm"].to_numpy(float), serial["mean_mm"].to_numpy(float), rtol=1e-12)


def test_invalid_and_unreachable_designs_are_rows_with_reasons():
    from rodlab.app.study import grid_candidates, prepare_design
    base = resolve_design("rod4")
    bad = grid_candidates(base, [40.0], [450.0])[0]
    assert bad.design is None and bad.invalid
    s = prepare_design(bad, resolve_robot("tx90"), standard_fixture(), 6, (1.0, 1.0))
    assert s.status == "invalid" and s.message
    far = replace(standard_fixture(), poses={j: np.asarray(p, float) + [0, 0, 3000.0, 0, 0, 0]
                                             for j, p in standard_fixture().poses.items()})
    ok = grid_candidates(base, [300.0], [450.0])[0]
    s = prepare_design(ok, resolve_robot("tx90"), far, 6, (1.0, 1.0), candidates=5)
    assert s.status == "unreachable" and "clamping position" in s.message


def test_study_command_end_to_end(tmp_path, capsys):
    import pandas as pd

    from rodlab.app.cli.main import main
    from rodlab.app.study import STUDY_COLUMNS
    out = tmp_path / "s"
    rc = main(["study", "rod4", "--L1", "250,300", "--L2", "450,500", "--replicates", "2", "--methods", "none,meas",
               "--no-calibrate", "--no-budget", "--serial", "-q", "-o", str(out)])
    assert rc == 0
    text = capsys.readouterr().out
    assert "recommendation: build" in text
    df = pd.read_csv(out / "study.csv")
    assert list(df.columns) == STUDY_COLUMNS
    assert set(df["method"]) == {"none", "meas"} and len(df) == 8
    assert (df[df["method"] == "meas"]["mean_mm"].to_numpy() < df[df["method"] == "none"]["mean_mm"].to_numpy()).all()
    for name in ("pareto.png", "heatmaps.png", "study.html"):
        assert (out / name).stat().st_size > 5000
    import json
    rec = json.loads((out / "study.json").read_text())["recommendation"]
    assert rec["text"].startswith("build") and rec["L1_mm"] in (250.0, 300.0) and rec["method"] == "meas"
    assert "Recommendation" in (out / "study.html").read_text()


@pytest.mark.parametrize("argv, msg", [
    (["--methods", "none,fee"], "--methods"),
    (["--r-prior-metal", "2:1"], "--r-prior-metal"),
    (["--replicates", "0"], "--replicates"),
    (["--tubes", "25-2"], "--tubes"),
])
def test_study_bad_options_name_the_option(tmp_path, capsys, argv, msg):
    from rodlab.app.cli.main import main
    try:
        rc = main(["study", "rod4", "--L1", "300", "--serial", "-o", str(tmp_path / "x"), *argv])
    except SystemExit as e:                          # argparse refuses a count < 1 itself
        rc = e.code
    assert rc == 2
    assert msg in capsys.readouterr().err
    assert not (tmp_path / "x" / "study.csv").exists()


def test_the_fixture_distance_places_the_clamping_positions_and_rules_out_rods_that_cannot_reach(tmp_path, capsys):
    """--fixture-distance-mm: {W} that far in front of the robot (a designer trial: the study could not be told the
    fixture was 700 mm away, so its shortest rod always won); at 1350 mm the TX90 reaches with the long rod only,
    the short one reported unreachable; the layout is on the page and the spec's base in study.json."""
    import json

    import pandas as pd

    from rodlab.app.cli.main import main
    from rodlab.calibrate.setup_layout import standard_base
    out = tmp_path / "far"
    rc = main(["study", "rod4", "--L1", "200,500", "--L2", "400,800", "--methods", "meas", "--draws", "16",
               "--no-calibrate", "--no-budget", "--serial", "-q", "--fixture-distance-mm", "1350", "-o", str(out)])
    assert rc == 0
    df = pd.read_csv(out / "study.csv").drop_duplicates("design").set_index("design")
    statuses = dict(zip(df["L1_mm"].astype(int).astype(str) + "-" + df["L2_mm"].astype(int).astype(str), df["status"]))
    assert statuses["200-400"] == "unreachable" and statuses["500-800"] == "ok"
    spec = json.loads((out / "study.json").read_text())["spec"]
    assert np.allclose(spec["base"], standard_base(1350.0))
    assert "1350 mm in front of the robot base" in (out / "study.html").read_text()
    with pytest.raises(SystemExit):
        main(["study", "rod4", "--fixture-distance-mm", "700", "--base", "0,0,0,0,0,0", "-o", str(out)])
    assert "not allowed with argument" in capsys.readouterr().err
