"""The pybotics side of benchmarks/realdata_pybotics.py, run inside the pybotics venv (pybotics pins numpy<2).

Reads a job (JSON on stdin): the nominal model as pybotics MDH rows [alpha rad, a mm, theta rad, d mm], tool
and world frames, a few nominal check points, the fit set and the test sets (q [rad], tracker points [mm],
starting world / tool for each). Calibrates the way pybotics' own example does: scipy ``least_squares`` on
``pybotics.optimization.optimize_accuracy`` (per-point distance residuals) with an ``OptimizationHandler``
freeing the kinematic chain (all but the first link, which the world frame absorbs), the tool position and the
world frame; then on each test set refits world frame and tool position with the chain held, as rodlab does.
Writes per-test-set errors [mm] as JSON on stdout.
"""
import json
import sys

import numpy as np
from pybotics.optimization import OptimizationHandler, compute_absolute_errors, optimize_accuracy
from pybotics.robot import Robot
from scipy.optimize import least_squares


def _robot(job, world, tool):
    robot = Robot.from_parameters(np.array(job["mdh"], float))
    robot.world_frame = np.array(world, float)
    robot.tool.matrix = np.array(tool, float)
    return robot


def _fit(robot, q, p, chain_mask):
    handler = OptimizationHandler(robot=robot, kinematic_chain_mask=chain_mask,
                                  tool_mask=[True, True, True, False, False, False], world_mask=[True] * 6)
    x0 = handler.generate_optimization_vector()
    res = least_squares(optimize_accuracy, x0, args=(handler, q, p))
    handler.apply_optimization_vector(res.x)
    return handler.robot


def main():
    job = json.load(sys.stdin)
    nominal = _robot(job, job["world"], job["tool"])
    for q, p in job["check"]:
        err = np.linalg.norm(nominal.fk(np.array(q))[:3, 3] - np.array(p))
        if err > 1e-6:
            raise SystemExit(f"pybotics nominal model differs from rodlab's by {err} mm: conversion error")
    mask = np.ones(nominal.kinematic_chain.num_parameters, bool)
    mask[:4] = False
    fit = job["fit"]
    robot = _fit(_robot(job, fit["world"], fit["tool"]), np.array(fit["q"]), np.array(fit["p"]), mask)
    fit_err = compute_absolute_errors(np.array(fit["q"]), np.array(fit["p"]), robot)
    out = {"fit_rms_mm": float(np.sqrt(np.mean(fit_err ** 2))), "tests": {}}
    for name, t in job["tests"].items():
        start = Robot(kinematic_chain=robot.kinematic_chain)
        start.world_frame, start.tool.matrix = np.array(t["world"], float), np.array(t["tool"], float)
        refit = _fit(start, np.array(t["q"]), np.array(t["p"]), False)
        out["tests"][name] = compute_absolute_errors(np.array(t["q"]), np.array(t["p"]), refit).tolist()
    json.dump(out, sys.stdout)


if __name__ == "__main__":
    main()
