"""``rodlab study``'s engine: every design (and, with Monte Carlo, every replicate) a Dask task, cached.

1. the joint calibration of each design family (one solid FEA run each, in this process; cad extra);
2. per design a preparation task (:func:`rodlab.app.study.prepare.prepare_design`);
3. the default (``spec.monte_carlo`` off): in the same task the linear predictor
   (:func:`rodlab.calibrate.predict_linear.predict_linear`) from the planned campaign, milliseconds to a
   second per design; with ``spec.monte_carlo`` per design and replicate a Monte-Carlo task
   (:func:`rodlab.calibrate.predict.run_replicate`), seeds ``seed + i`` — the same seeds for every design, so
   designs are compared on the same draws (the linear predictor's draws are seeded alike);
4. the summaries per design and method (:func:`rodlab.calibrate.predict.summarise`) as the study table.

Results are cached under ``cache_dir/<design key>/`` (``setup.json``, ``rep_<seed>.json``, or ``fast.json``
for the linear predictor); the key hashes
everything that changes a result (the design's numbers, robot, fixture, priors, methods, orientations, the
joint calibration, rodlab's version), so a re-run computes only what is missing and an interrupted study
resumes. Dask runs on a ``LocalCluster`` by default, on ``scheduler=ADDRESS`` when given, or serially.
"""
from __future__ import annotations

import hashlib
import json
import logging
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Callable

import numpy as np

from rodlab import __version__
from rodlab.calibrate import CalibrationError
from rodlab.calibrate.predict import Priors, ReplicateOutcome, run_replicate
from rodlab.calibrate.simulate import standard_base
from rodlab.calibrate.validate import ErrorStats
from rodlab.core.cluster import ONE_THREAD_ENV, local_cluster
from rodlab.core.design_io import design_to_dict
from rodlab.core.enums import Method
from rodlab.core.fileio import atomic_write_json, json_safe

from .designs import Candidate, r_prior_of
from .prepare import DesignSetup, prepare_design

__all__ = ["StudySpec", "run_study", "StudyRun"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class StudySpec:
    """How a study predicts: ``methods`` (contract spellings), ``replicates`` per design, ``orientations``
    per clamping position, ``priors`` (:class:`rodlab.calibrate.predict.Priors`; its ``r_rod`` is replaced per
    design by ``r_prior_metal`` / ``r_prior_composite``), ``seed``, ``budget`` (the error budget's extra
    identification per replicate), ``monte_carlo`` (simulate ``replicates`` campaigns per design instead of the
    linear predictor's ``draws``), ``base`` (shape=(6,) the robot base {0} in {W} [mm, deg]; None: the simulator's
    standard layout, {W} 650 mm in front of the robot, 250 mm up)."""

    methods: tuple = ("none", "calc", "fea", "meas")
    replicates: int = 20
    orientations: int = 6
    priors: object = None
    r_prior_metal: tuple = (1.01, 1.05)
    r_prior_composite: tuple = (1.23, 2.30)
    seed: int = 0
    budget: bool = True
    monte_carlo: bool = False
    draws: int = 256
    base: tuple | None = None

    def base_pose(self) -> np.ndarray:
        """The robot base {0} in {W} [mm, deg], shape=(6,)."""
        return standard_base() if self.base is None else np.asarray(self.base, float)


@dataclass
class StudyRun:
    """A finished study: per design its setup and its replicate outcomes (in seed order; Monte Carlo) or its
    linear prediction (:class:`rodlab.calibrate.predict_linear.LinearPrediction`, else None)."""

    setups: list
    outcomes: list
    spec: StudySpec
    timings: dict = field(default_factory=dict)
    predictions: list = field(default_factory=list)


def replicate_priors(spec: StudySpec, setup_or_prior):
    base = spec.priors or Priors()
    return replace(base, r_rod=tuple(setup_or_prior))


def joints_identity(joints) -> str | None:
    """What a family's joint calibration is made from (its solid-run design and the frame constants), not its
    numbers: a repeated solid run differs in the last digits (threaded sparse solver), which must not
    invalidate a cache."""
    if joints is None:
        return None
    return json.dumps({"base": design_to_dict(joints.base), "calibration": repr(joints.calibration)},
                      sort_keys=True, default=str)


#: what a cache entry holds; raised when that changes within one rodlab version (2: the budget's slip share, which
#: an entry written before would read as 0)
CACHE_FORMAT = 2


def cache_key(cand: Candidate, robot, fixture, spec: StudySpec, joints) -> str:
    blob = {"design": design_to_dict(cand.design) if cand.design else cand.invalid, "label": cand.label,
            "robot": repr(robot), "fixture": {str(k): list(map(float, v)) for k, v in fixture.poses.items()},
            "force": list(map(float, fixture.force_D_N)), "spec": repr(spec), "joints": joints_identity(joints),
            "v": __version__, "cache": CACHE_FORMAT,     # the r_rod prior: an as-built design's comes from its file
            "r_prior": (r_prior_of(cand.design, spec.r_prior_metal, spec.r_prior_composite) if cand.design else None)}
    return hashlib.sha256(json.dumps(blob, sort_keys=True, default=str).encode()).hexdigest()[:20]


def outcome_to_dict(o) -> dict:
    return {"seed": o.seed, "r_true": o.r_true, "stats": {str(m): s.to_dict() for m, s in o.stats.items()},
            "ms_mm2": {str(m): v for m, v in o.ms_mm2.items()}, "ms_true_rod_mm2": o.ms_true_rod_mm2,
            "ms_clean_mm2": o.ms_clean_mm2, "success": {str(m): v for m, v in o.success.items()},
            "before": o.before.to_dict(), "ms_true_no_slip_mm2": o.ms_true_no_slip_mm2}


def _float(v) -> float:
    return float("nan") if v is None else float(v)


def outcome_from_dict(d: dict):
    return ReplicateOutcome(int(d["seed"]), float(d["r_true"]),
                            {Method.parse(m): ErrorStats(**s) for m, s in d["stats"].items()},
                            {Method.parse(m): float(v) for m, v in d["ms_mm2"].items()},
                            _float(d["ms_true_rod_mm2"]), _float(d["ms_clean_mm2"]),
                            {Method.parse(m): bool(v) for m, v in d["success"].items()}, ErrorStats(**d["before"]),
                            _float(d.get("ms_true_no_slip_mm2")))


def _prepare_task(cand, robot, fixture, spec, joints) -> dict:
    prior = r_prior_of(cand.design, spec.r_prior_metal, spec.r_prior_composite) if cand.design else (1.0, 1.0)
    return prepare_design(cand, robot, fixture, spec.orientations, prior, joints, seed=spec.seed,
                          base=spec.base_pose()).to_dict()


def _replicate_task(setup: dict, robot, fixture, spec: StudySpec, seed: int) -> dict | None:
    s = DesignSetup.from_dict(setup)
    if not s.ok:
        return None
    try:
        o = run_replicate(robot, s.plan_q_rad, fixture, spec.base_pose(), s.fea, s.calc, spec.methods,
                          replicate_priors(spec, s.r_prior), seed, spec.budget)
    except CalibrationError as e:
        return {"seed": seed, "error": str(e)}
    return outcome_to_dict(o)


class ResultCache:
    def __init__(self, root: Path | None):
        self.root = root

    def _path(self, key, name):
        return None if self.root is None else self.root / key / name

    def get(self, key, name):
        p = self._path(key, name)
        if p is None or not p.exists():
            return None
        try:
            return json.loads(p.read_text())
        except (OSError, ValueError):
            log.warning("ignoring unreadable cache entry %s", p)
            return None

    def put(self, key, name, value):
        p = self._path(key, name)
        if p is not None:
            atomic_write_json(p, json_safe(value))          # NaN (not computed) stored as null


def dask_client(scheduler, workers):
    """(client, local cluster or None) on ``scheduler`` or a local cluster of ``workers``; (None, None) with a
    warning when Dask is not installed (the study then runs serially)."""
    try:
        from dask.distributed import Client
    except ImportError:
        log.warning("Dask is not installed (pip install 'rodlab[dist]'): the study runs serially")
        return None, None
    if not log.isEnabledFor(logging.DEBUG):      # the cluster's start / stop chatter only with --debug
        for name in ("distributed", "distributed.scheduler", "distributed.nanny", "distributed.core",
                     "distributed.worker", "distributed.http.proxy"):
            logging.getLogger(name).setLevel(logging.WARNING)
    if scheduler:
        return Client(scheduler), None
    cluster = local_cluster(workers, env=dict(ONE_THREAD_ENV))                # small matrices
    return Client(cluster), cluster


def run_study(cands: list[Candidate], robot, fixture, spec: StudySpec = StudySpec(), joints: dict | None = None,
              cache_dir=None, scheduler: str | None = None, workers: int = 2, use_dask: bool = True,
              progress: Callable[[int, int], None] | None = None) -> StudyRun:
    """Run the study (see the module docstring). ``joints``: {candidate label: JointCalibration or None}."""
    joints = joints or {}
    if not spec.monte_carlo:
        from .run_fast import run_fast  # cycle: run_fast imports this module's helpers
        return run_fast(cands, robot, fixture, spec, joints, cache_dir, scheduler, workers, use_dask, progress)
    cache = ResultCache(Path(cache_dir) if cache_dir else None)
    keys = [cache_key(c, robot, fixture, spec, joints.get(c.label)) for c in cands]
    seeds = [spec.seed + i for i in range(int(spec.replicates))]
    setups = [cache.get(k, "setup.json") for k in keys]
    reps = [[cache.get(k, f"rep_{s}.json") for s in seeds] for k in keys]
    total = len(cands) * (1 + len(seeds))
    done = sum(s is not None for s in setups) + sum(r is not None for rr in reps for r in rr)
    tick = progress_ticker(progress, done, total)
    client = cluster = None
    if use_dask and done < total:
        client, cluster = dask_client(scheduler, workers)
    try:
        if client is not None:
            _run_dask(client, cands, keys, seeds, setups, reps, robot, fixture, spec, joints, cache, tick)
        else:
            _run_serial(cands, keys, seeds, setups, reps, robot, fixture, spec, joints, cache, tick)
    finally:
        if client is not None:
            client.close()
        if cluster is not None:
            cluster.close()
    outcomes = [[outcome_from_dict(r) for r in rr if r is not None and "error" not in r] for rr in reps]
    return StudyRun([DesignSetup.from_dict(s) for s in setups], outcomes, spec)


def progress_ticker(progress, done, total):
    state = {"done": done}
    if progress:
        progress(done, total)

    def tick(n=1):
        state["done"] += n
        if progress:
            progress(state["done"], total)
    return tick


def _run_serial(cands, keys, seeds, setups, reps, robot, fixture, spec, joints, cache, tick):
    for i, (c, k) in enumerate(zip(cands, keys)):
        if setups[i] is None:
            setups[i] = _prepare_task(c, robot, fixture, spec, joints.get(c.label))
            cache.put(k, "setup.json", setups[i])
            tick()
        for r, s in enumerate(seeds):
            if reps[i][r] is None:
                reps[i][r] = _replicate_task(setups[i], robot, fixture, spec, s) or {"seed": s, "error": "skipped"}
                cache.put(k, f"rep_{s}.json", reps[i][r])
                tick()


def _run_dask(client, cands, keys, seeds, setups, reps, robot, fixture, spec, joints, cache, tick):
    from dask.distributed import as_completed
    robot_f, fixture_f, spec_f = client.scatter([robot, fixture, spec], broadcast=True)
    futures = {}
    setup_f = []
    for i, (c, k) in enumerate(zip(cands, keys)):
        if setups[i] is None:
            f = client.submit(_prepare_task, c, robot_f, fixture_f, spec_f, joints.get(c.label), pure=False)
            futures[f] = ("setup", i, None)
        else:
            f = setups[i]
        setup_f.append(f)
        for r, s in enumerate(seeds):
            if reps[i][r] is None:
                futures[client.submit(_replicate_task, f, robot_f, fixture_f, spec_f, s, pure=False)] = ("rep", i, r)
    for fut in as_completed(list(futures)):
        what, i, r = futures[fut]
        value = fut.result()
        if what == "setup":
            setups[i] = value
            cache.put(keys[i], "setup.json", value)
        else:
            reps[i][r] = value or {"seed": seeds[r], "error": "skipped"}
            cache.put(keys[i], f"rep_{seeds[r]}.json", reps[i][r])
        tick()


def spec_dict(spec: StudySpec) -> dict:
    """The spec as plain data (for the study's provenance)."""
    d = asdict(replace(spec, priors=None))
    d["priors"] = asdict(spec.priors) if spec.priors is not None else None
    return d

