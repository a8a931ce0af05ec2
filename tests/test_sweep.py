"""Design sweeps: Dask equals serial, invalid designs are rows, a re-run resumes from the cache."""
from __future__ import annotations

import numpy as np
import pytest

from fea.sweep import SWEEP_COLUMNS, parse_range, run_sweep
from rodlab import FormatError, resolve_design


def test_parse_range():
    np.testing.assert_allclose(parse_range("150:250:50", "L1"), [150, 200, 250])
    np.testing.assert_allclose(parse_range("300,350", "L2"), [300, 350])
    with pytest.raises(FormatError, match="L1"):
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
