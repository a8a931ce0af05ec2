"""L1 / L2 design sweeps: every design validated, its compliance, c_rod, mass and tool point, on Dask.

Runs on a Dask ``LocalCluster`` by default, on an existing cluster with ``scheduler=ADDRESS``, or serially
when Dask is not installed (``dist`` extra). Results are cached per design hash in ``cache_dir`` (one JSON
each), so a re-run computes only what is missing; an invalid or failing design is a row with its message,
never fatal. The library reports progress through a callback; the CLI prints it.
"""
from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import replace
from pathlib import Path
from typing import Callable

import numpy as np

from rodlab import __version__
from rodlab.core.cluster import local_cluster
from rodlab.core.design import RodDesign
from rodlab.core.errors import RodlabError
from rodlab.core.fileio import atomic_write_json

from .compute import FeaModel, compute_compliance
from .errors import FeaError
from .frame import CALIBRATED_RANGE, CALIBRATION, FRAME_REVISION

__all__ = ["parse_range", "sweep_designs", "run_sweep", "SWEEP_COLUMNS"]

log = logging.getLogger(__name__)

SWEEP_COLUMNS = (["L1_mm", "L2_mm", "status", "message", "c_rod_um", "mass_kg", "x_tool_mm", "z_tool_mm"]
                 + [f"CF{i}{j}_mm_per_N" for i in range(1, 4) for j in range(1, 4)]
                 + [f"Cg{i}{j}_mm_per_g0" for i in range(1, 4) for j in range(1, 4)] + ["design_hash"])


def parse_range(text: str, name: str) -> np.ndarray:
    """``START:STOP:STEP`` (inclusive stop), ``a,b,c`` or a single value [mm]."""
    try:
        if ":" in text:
            a, b, s = (float(v) for v in text.split(":"))
            if s <= 0 or b < a:
                raise ValueError
            return np.round(np.arange(a, b + 0.5 * s, s), 9)
        return np.array([float(v) for v in text.split(",")])
    except ValueError as e:
        raise FeaError(f"expected START:STOP:STEP with STEP > 0 and STOP >= START, or a,b,c; got {text!r}",
                       key=name) from e


def _key(design_summary: dict, model: str, calibration=None) -> str:
    blob = json.dumps({"d": design_summary, "m": model, "v": __version__, "cal": repr(calibration or CALIBRATION),
                       "frame": FRAME_REVISION, "range": repr(sorted(CALIBRATED_RANGE.items()))}, sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()[:20]


def _evaluate(base: RodDesign, L1: float, L2: float, model: str, mesher, calibration=None) -> dict:
    row = {"L1_mm": float(L1), "L2_mm": float(L2)}
    try:
        d = replace(base, L1_mm=float(L1), L2_mm=float(L2), name=f"{base.name} {L1:g}-{L2:g}")
    except RodlabError as e:
        return dict(row, status="invalid", message=str(e))
    try:
        opts = {"error_estimate": False} if model == "solid" else (
            {"calibration": calibration} if model == "frame" and calibration is not None else {})
        comp = compute_compliance(d, FeaModel(model), mesher=mesher, **opts)
    except Exception as e:  # noqa: BLE001 - a failing design is a row, never fatal
        return dict(row, status="failed", message=f"{type(e).__name__}: {e}")
    notes = comp.provenance.get("outside_calibrated_range") or []
    row.update(status="ok", message="; ".join(notes), c_rod_um=comp.c_rod_um, mass_kg=comp.mass_kg,
               x_tool_mm=float(d.tool_mm[0]), z_tool_mm=float(d.tool_mm[2]))
    for i in range(3):
        for j in range(3):
            row[f"CF{i + 1}{j + 1}_mm_per_N"] = float(comp.C_F[i, j])
            row[f"Cg{i + 1}{j + 1}_mm_per_g0"] = float(comp.C_g[i, j])
    return row


def _evaluate_batch(base, pairs, model, mesher, calibration=None):
    return [_evaluate(base, L1, L2, model, mesher, calibration) for L1, L2 in pairs]


def sweep_designs(base: RodDesign, L1s, L2s) -> list[tuple[float, float]]:
    """All (L1, L2) pairs of the grid [mm]."""
    return [(float(a), float(b)) for a in L1s for b in L2s]


def run_sweep(base: RodDesign, L1s, L2s, model: str = "frame", scheduler: str | None = None,
              workers: int = 2, cache_dir: str | Path | None = None, mesher=None, use_dask: bool = True,
              progress: Callable[[int, int], None] | None = None, batch: int | None = None, calibration=None):
    """Sweep L1 x L2 around ``base``; return a pandas DataFrame with :data:`SWEEP_COLUMNS`.

    ``model``: ``frame`` (default), ``calc`` or ``solid`` (needs ``mesher``, see :func:`fea.solid_compliance`).
    ``calibration``: for the frame, a :class:`fea.frame.FrameCalibration` (constants) or a
    :class:`fea.joints.JointFit` (one solid run of the family: :func:`fea.run_solid` with
    ``joints=True`` on :func:`fea.family.joint_fit_member`).
    """
    import pandas as pd

    pairs = sweep_designs(base, L1s, L2s)
    store = _SweepStore(Path(cache_dir) if cache_dir else None, len(pairs), progress)
    todo = store.load_cached(base, pairs, model, calibration)
    size = batch or (1 if model == "solid" else 25)
    chunks = [todo[i:i + size] for i in range(0, len(todo), size)]
    if todo and use_dask and _run_on_dask(chunks, store, base, model, mesher, calibration, scheduler, workers):
        chunks = []
    for ch in chunks:
        store.add(_evaluate_batch(base, [(a, b) for a, b, _ in ch], model, mesher, calibration), [k for _, _, k in ch])
    rows = store.rows
    df = pd.DataFrame([rows[p] for p in pairs])
    for c in SWEEP_COLUMNS:
        if c not in df:
            df[c] = np.nan if c not in ("status", "message", "design_hash") else ""
    return df[SWEEP_COLUMNS]


class _SweepStore:
    """The sweep's rows as they arrive, each written to the cache (one JSON per design, by its hash) and
    counted for ``progress(done, total)``."""

    def __init__(self, cache: Path | None, n_total: int, progress) -> None:
        self.cache, self.n_total, self.progress = cache, n_total, progress
        self.rows: dict[tuple, dict] = {}
        self.n_done = 0

    def load_cached(self, base: RodDesign, pairs, model: str, calibration) -> list[tuple[float, float, str]]:
        """Take every design already in the cache; returns the (L1, L2, key) still to evaluate."""
        todo = []
        summary = base.summary()
        for L1, L2 in pairs:
            key = _key(dict(summary, L1_mm=L1, L2_mm=L2, name=None), model, calibration)
            f = self.cache / f"{key}.json" if self.cache else None
            if f is not None and f.exists():
                try:
                    self.rows[(L1, L2)] = dict(json.loads(f.read_text()), design_hash=key)
                    self.n_done += 1
                    continue
                except (OSError, ValueError):
                    log.warning("ignoring unreadable cache entry %s", f)
            todo.append((L1, L2, key))
        self._report()
        return todo

    def add(self, result_rows, keys) -> None:
        for r, key in zip(result_rows, keys):
            r["design_hash"] = key
            self.rows[(r["L1_mm"], r["L2_mm"])] = r
            if self.cache is not None:
                atomic_write_json(self.cache / f"{key}.json", {k: v for k, v in r.items() if k != "design_hash"})
        self.n_done += len(result_rows)
        self._report()

    def _report(self) -> None:
        if self.progress:
            self.progress(self.n_done, self.n_total)


def _run_on_dask(chunks, store: _SweepStore, base, model, mesher, calibration, scheduler, workers) -> bool:
    """Evaluate the chunks on a Dask cluster (``scheduler``'s, or a local one of ``workers`` processes);
    False when Dask is not installed (the caller runs them serially)."""
    try:
        from dask.distributed import Client, as_completed
    except ImportError:
        log.warning("Dask is not installed (pip install 'rodlab[dist]'): the sweep runs serially in this process")
        return False
    cluster = None
    if scheduler:
        client = Client(scheduler)
    else:
        cluster = local_cluster(workers)
        client = Client(cluster)
    try:
        futures = {client.submit(_evaluate_batch, base, [(a, b) for a, b, _ in ch], model, mesher,
                                 calibration, pure=False): ch for ch in chunks}
        for fut in as_completed(futures):
            store.add(fut.result(), [k for _, _, k in futures[fut]])
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return True
