"""``rodlab study``'s default engine: one task per design — its preparation and the linear predictor
(:func:`rodlab.calibrate.predict_linear.predict_linear`) from its planned campaign — on Dask or serially,
cached per design as ``cache_dir/<design key>/fast.json`` (the key as for Monte Carlo, :mod:`.run`)."""
from __future__ import annotations

import logging
from pathlib import Path

from rodlab.calibrate import CalibrationError
from rodlab.calibrate.predict import AccuracySummary, BudgetShares
from rodlab.calibrate.predict_linear import LinearPrediction, predict_linear
from rodlab.core.blas_threads import one_blas_thread
from rodlab.core.enums import DesignStatus, Method

from .designs import r_prior_of
from .prepare import DesignSetup, prepare_design, study_reason
from .run import ResultCache, StudyRun, cache_key, dask_client, progress_ticker, replicate_priors

__all__ = ["run_fast", "prediction_to_dict", "prediction_from_dict", "DASK_MIN_DESIGNS"]

log = logging.getLogger(__name__)

#: fewer designs than this run in this process: a local cluster's start (~5-15 s on 2 cores, each worker
#: importing rodlab) costs more than ~0.5 s per design saves (an address given with ``scheduler`` is always used)
DASK_MIN_DESIGNS = 16


def prediction_to_dict(lp) -> dict:
    """A :class:`~rodlab.calibrate.predict_linear.LinearPrediction` as plain data (its draws' means left out)."""
    keys = ("mean_mm", "max_mm", "median_mm", "mean_p05_mm", "mean_p95_mm", "rms_mm", "replicates", "failed")
    return {"draws": lp.draws, "nominal_mean_mm": lp.nominal_mean_mm, "ms_noise_mm2": lp.ms_noise_mm2,
            "summaries": [{"method": str(a.method), **{k: getattr(a, k) for k in keys},
                           "budget": a.budget.to_dict()} for a in lp.summaries]}


def _f(v) -> float:
    return float("nan") if v is None else float(v)


def prediction_from_dict(d: dict):
    out = []
    for a in d["summaries"]:
        b = BudgetShares.from_dict(a["budget"])
        out.append(AccuracySummary(Method.parse(a["method"]), *(_f(a[k]) for k in (
            "mean_mm", "max_mm", "median_mm", "mean_p05_mm", "mean_p95_mm", "rms_mm")), b, int(a["replicates"]),
            int(a["failed"])))
    return LinearPrediction(out, _f(d["nominal_mean_mm"]), _f(d["ms_noise_mm2"]), int(d["draws"]))


def _fast_task(cand, robot, fixture, spec, joints) -> dict:
    """One design: its setup and its linear prediction (None for a design that is not usable); a prediction
    that fails marks the design failed with the reason."""

    prior = r_prior_of(cand.design, spec.r_prior_metal, spec.r_prior_composite) if cand.design else (1.0, 1.0)
    s = prepare_design(cand, robot, fixture, spec.orientations, prior, joints, seed=spec.seed, base=spec.base_pose())
    if not s.ok:
        return {"setup": s.to_dict(), "prediction": None}
    try:
        lp = predict_linear(robot, s.plan_q_rad, fixture, spec.base_pose(), s.fea, s.calc, spec.methods,
                            replicate_priors(spec, s.r_prior), spec.draws, spec.seed)
    except CalibrationError as e:
        s.status, s.message = DesignStatus.FAILED, study_reason(e)
        return {"setup": s.to_dict(), "prediction": None}
    return {"setup": s.to_dict(), "prediction": prediction_to_dict(lp)}


def run_fast(cands, robot, fixture, spec, joints: dict, cache_dir, scheduler, workers: int, use_dask: bool,
             progress):
    """:func:`rodlab.app.study.run.run_study` with the linear predictor (``spec.monte_carlo`` off)."""
    cache = ResultCache(Path(cache_dir) if cache_dir else None)
    keys = [cache_key(c, robot, fixture, spec, joints.get(c.label)) for c in cands]
    got = [cache.get(k, "fast.json") for k in keys]
    tick = progress_ticker(progress, sum(g is not None for g in got), len(cands))
    todo = [i for i, g in enumerate(got) if g is None]
    client = cluster = None
    if use_dask and (scheduler or len(todo) >= DASK_MIN_DESIGNS):
        client, cluster = dask_client(scheduler, workers)
    try:
        if client is not None:
            _dask(client, cands, keys, todo, got, robot, fixture, spec, joints, cache, tick)
        else:
            with one_blas_thread():       # a design's small matrices: 1.5x faster than two OpenBLAS threads
                for i in todo:
                    got[i] = _fast_task(cands[i], robot, fixture, spec, joints.get(cands[i].label))
                    cache.put(keys[i], "fast.json", got[i])
                    tick()
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    setups = [DesignSetup.from_dict(g["setup"]) for g in got]
    preds = [prediction_from_dict(g["prediction"]) if g.get("prediction") else None for g in got]
    return StudyRun(setups, [[] for _ in got], spec, predictions=preds)


def _dask(client, cands, keys, todo, got, robot, fixture, spec, joints, cache, tick):
    from dask.distributed import as_completed
    robot_f, fixture_f, spec_f = client.scatter([robot, fixture, spec], broadcast=True)
    futures = {client.submit(_fast_task, cands[i], robot_f, fixture_f, spec_f, joints.get(cands[i].label),
                             pure=False): i for i in todo}
    for fut in as_completed(list(futures)):
        i = futures[fut]
        got[i] = fut.result()
        cache.put(keys[i], "fast.json", got[i])
        tick()
