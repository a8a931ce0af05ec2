"""Design sweeps: Dask equals serial, invalid designs are rows, a re-run resumes from the cache."""
from __future__ import annotations

import numpy as np
import pytest

from rodlab.fea.sweep import SWEEP_COLUMNS, parse_range, run_sweep
from rodlab import resolve_design
from conftest import legacy_design, legacy_file
from rodlab.core.errors import LocatedError


def test_parse_range():
    np.testing.assert_allclose(parse_range("150:250:50", "L1"), [150, 200, 250])
    np.testing.assert_allclose(parse_range("300,350", "L2"), [300, 350])
    with pytest.raises(LocatedError, match="L1"):
        parse_range("150:100:10", "L1")


def test_serial_sweep_reports_invalid_designs_and_resumes(tmp_path):
    base = resolve_design("rod1")
    calls = []
    df = run_sweep(base, [100.0, 300.0], [450.0, 500.0], use_dask=False, cache_dir=tmp_path,
                   progress=lambda d, n: calls.append((d, n)))
    assert list(df.columns) == SWEEP_COLUMNS and len(df) == 4
    bad = df[df["L1_mm"] == 100.0]
    assert (bad["status"] == "invalid").all() and bad["message"].str.contains("L1_mm").all()
    ok = df[df["status"] == "ok"]
    assert len(ok) == 2 and (ok["c_rod_um"] > 0).all()
    assert calls[0] == (0, 4) and calls[-1] == (4, 4)
    calls.clear()
    again = run_sweep(base, [100.0, 300.0], [450.0, 500.0], use_dask=False, cache_dir=tmp_path,
                      progress=lambda d, n: calls.append((d, n)))
    assert calls == [(4, 4)]                      # everything came from the cache
    assert again.drop(columns="message").equals(df.drop(columns="message"))


def test_dask_local_cluster_equals_serial(tmp_path):
    pytest.importorskip("dask.distributed")
    base = resolve_design("rod4")
    L1s, L2s = [250.0, 300.0, 350.0], [400.0, 450.0]
    serial = run_sweep(base, L1s, L2s, use_dask=False)
    parallel = run_sweep(base, L1s, L2s, use_dask=True, workers=2, batch=2)
    num = [c for c in SWEEP_COLUMNS if c.endswith(("_um", "_kg", "_mm_per_N", "_mm_per_g0"))]
    np.testing.assert_allclose(parallel[num].to_numpy(float), serial[num].to_numpy(float), rtol=1e-12)
    assert (parallel["status"] == serial["status"]).all()


def test_sweep_cli_writes_table_and_plot(tmp_path, capsys):
    """``rodlab sweep``: the table's rows are the frame model of each L1 x L2 variant, a heat map is written,
    and bad options are one clear line (exit 2)."""
    import pandas as pd
    from rodlab.fea import compute_compliance
    from rodlab.app.cli import main
    out = tmp_path / "s.csv"
    assert main(["sweep", "--L1", "150,300", "--L2", "450,525", "--serial", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    df = pd.read_csv(out)
    assert len(df) == 4 and (df["status"] == "ok").all()
    ref = compute_compliance(resolve_design("rod2"), "frame")        # rod 2#: rod 1#'s sections at 150 / 525
    row = df[(df["L1_mm"] == 150.0) & (df["L2_mm"] == 525.0)].iloc[0]
    for i in range(3):
        assert row[f"CF{i + 1}{i + 1}_mm_per_N"] == pytest.approx(ref.C_F[i, i], rel=1e-9)
        assert row[f"Cg{i + 1}3_mm_per_g0"] == pytest.approx(ref.C_g[i, 2], rel=1e-9, abs=1e-12)
    assert row["c_rod_um"] == pytest.approx(ref.c_rod_um, rel=1e-9)
    assert (tmp_path / "s.png").stat().st_size > 10_000
    assert "4 designs (4 ok" in text and "stiffest: L1 = 150" in text
    for bad, says in ((["--model", "calc", "--calibrate"], "--calibrate applies to --model frame"),
                      (["-o", str(tmp_path / "s.txt")], "must end in .csv or .parquet"),
                      (["--L1", "300:150:10"], "L1")):
        args = ["sweep", "--L1", "150", "--L2", "450", "--serial", "-o", str(out)] + bad
        assert main(args) == 2
        err = capsys.readouterr().err
        assert says in err and "Traceback" not in err


@pytest.mark.cad
def test_sweep_cli_calibrate_matches_the_solid_family(tmp_path, capsys):
    """``rodlab sweep --calibrate``: one solid FEA run of the base (4#) calibrates the frame's joints, and the
    family's other paper rods (5#, 6#: same parts, other L1 / L2) then agree with their own solid FEA
    (fea/data/solid_reference.json) within 0.1 % on every significant entry (the global frame: 0.74 %)."""
    import json
    from pathlib import Path

    import pandas as pd
    from rodlab.app.cli import main
    pytest.importorskip("gmsh")
    refs = json.loads((Path(__file__).resolve().parents[1] / "fea" / "data" / "solid_reference.json").read_text())
    out = tmp_path / "s.csv"
    rod4 = str(legacy_file(tmp_path / "rod4.rod.toml", "rod4"))     # the design of the stored solid family
    assert main(["sweep", "--base", rod4, "--L1", "150,375", "--L2", "525,600", "--serial", "--calibrate",
                 "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "frame joint-calibrated on the solid FEA of 4# (sections 20.0 / 20.0 mm" in text
    joints = tmp_path / "s.joints.json"
    assert f"saved to {joints}" in text
    df = pd.read_csv(out)
    # calibrated once: the stored calibration gives the same table, and rodlab fea the same member
    assert main(["sweep", "--base", rod4, "--L1", "150,375", "--L2", "525,600", "--serial", "--joints",
                 str(joints), "-o", str(tmp_path / "s2.csv")]) == 0
    pd.testing.assert_frame_equal(pd.read_csv(tmp_path / "s2.csv").drop(columns="design_hash"),
                                  df.drop(columns="design_hash"))
    rod5 = str(legacy_file(tmp_path / "rod5.rod.toml", "rod5"))
    assert main(["fea", rod5, "--model", "frame", "--joints", str(joints), "-o", str(tmp_path / "r5.json")]) == 0
    r5 = json.loads((tmp_path / "r5.json").read_text())
    assert r5["provenance"]["joint_calibration"]["solid_design"] == "4#"
    row5 = df[(df["L1_mm"] == 150.0) & (df["L2_mm"] == 525.0)].iloc[0]
    assert r5["c_rod_um"] == pytest.approx(row5["c_rod_um"], rel=1e-6)     # the file rounds c_rod
    capsys.readouterr()
    for bad, says in ((["--base", "rod1", "--joints", str(joints)], "1# is not a member of 4#'s family"),
                      (["--base", rod4, "--joints", str(joints), "--calibrate"], "not both"),
                      (["--base", rod4, "--joints", str(joints), "--model", "calc"], "--joints applies to")):
        assert main(["sweep", "--L1", "150", "--L2", "525", "--serial", "-o", str(tmp_path / "x.csv")] + bad) == 2
        err = capsys.readouterr().err
        assert says in err and "Traceback" not in err, err
    for name in ("rod5", "rod6"):
        d = legacy_design(name)
        row = df[(df["L1_mm"] == d.L1_mm) & (df["L2_mm"] == d.L2_mm)].iloc[0]
        for key, col in (("C_F", "CF{}{}_mm_per_N"), ("C_g", "Cg{}{}_mm_per_g0")):
            ref = np.asarray(refs[name][key])
            mine = np.array([[row[col.format(i + 1, j + 1)] for j in range(3)] for i in range(3)])
            big = np.abs(ref) > 0.02 * np.abs(ref).max()
            assert np.abs(mine[big] / ref[big] - 1).max() < 0.001, (name, key)


def _worker_environment():
    import os
    return {k: os.environ.get(k) for k in ("MALLOC_TRIM_THRESHOLD_", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")}


def test_local_cluster_workers_keep_glibcs_allocator_defaults(monkeypatch):
    """The workers of rodlab's local cluster run one BLAS thread and without Dask's ``MALLOC_TRIM_THRESHOLD_``
    (a fixed threshold maps and unmaps every array above 128 kB: a fifth of the study's worker time went to the
    kernel)."""
    pytest.importorskip("dask.distributed")
    from dask.distributed import Client
    from rodlab.core.cluster import ONE_THREAD_ENV, local_cluster
    for var in ("MALLOC_TRIM_THRESHOLD_", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS"):   # not inherited (conftest)
        monkeypatch.delenv(var, raising=False)
    cluster = local_cluster(1, env=dict(ONE_THREAD_ENV))
    try:
        with Client(cluster) as client:
            (env,) = client.run(_worker_environment).values()
    finally:
        cluster.close()
    assert env == {"MALLOC_TRIM_THRESHOLD_": None, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
