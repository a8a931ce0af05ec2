"""Held-out accuracy on public real tracker data: rodlab from the robot's URDF beside a kinematic-only model and
pybotics, on the same splits.

Data sets (``--data``, default all):

  fanuc  benchmarks/data/boby2021: FANUC R-2000iC/165F, three reflectors (see realdata_fanuc.py), the built-in
         URDF ``r2000ic165f``; splits: interleaved halves of every reflector; fit on N2, validate on N1 and N3.
  ur10   benchmarks/data/landgraf2021: Universal Robots UR10, a T-Mac measured by a laser tracker in three
         campaigns B, C, D (scripts/convert_landgraf2021.py), the built-in URDF ``ur10``; splits: interleaved
         halves of every series; fit on C (random poses), validate on B and D (other campaigns).
  ur5    benchmarks/data/jacobi2025: Universal Robots UR5, an SMR measured by a laser tracker on a 1,000-pose grid
         and 20 random poses (scripts/convert_jacobi2025.py), the built-in URDF ``ur5``; splits: interleaved
         halves of the grid; fit on the grid, validate on the random poses (the source's own split).

Per split and per model, the validation errors after the base and tool are refitted on the validation set
(paper Section 5.2):

  nominal          the URDF as it is;
  rodlab           kinematics (Hayati beta on the parallel J2/J3 pair), base, tool, joint compliances;
  kinematic only   the same with every joint compliance held at 0;
  rodlab + diag.   rodlab with the periodic joint errors that ``rodlab diagnose --points`` names on the fit set
                   identified too (``--joint-harmonics``; the joints named in brackets, "-" when none is named);
  pybotics         pybotics 3 (modified DH, its OptimizationHandler and scipy least_squares, as in its own
                   example; benchmarks/pybotics_side.py), from the same starting base and tool.

pybotics pins numpy<2, so it runs in its own venv: created on first use in benchmarks/.cache/pybotics-venv
(``pip install pybotics``), or give ``--python`` an interpreter that has it. Without it the pybotics column is
skipped with the reason.

    python benchmarks/realdata_pybotics.py [--data fanuc|ur10|ur5|all] [--python PY]
"""
from __future__ import annotations

import argparse
import json
import logging
import subprocess
import sys
import time
import venv
from pathlib import Path

import numpy as np

from rodlab.calibrate import ModelParams, read_points, register_base_and_tool, resolve_robot
from rodlab.calibrate.holdout import fit_and_validate, interleaved
from rodlab.calibrate.kinematics import forward
from rodlab.calibrate.points import points_observations
from rodlab.calibrate.robot_lines import row_matrix
from rodlab.calibrate.validate import error_stats
from rodlab.core.frames import pose_to_matrix

HERE = Path(__file__).parent
VENV = HERE / ".cache" / "pybotics-venv"


def _interleaved(pts: dict) -> list:
    out = []
    for name, p in pts.items():
        fit, test = interleaved(p)
        out.append(("interleaved", fit, [(name + " odd poses", test)]))
    return out


def fanuc_splits():
    data = HERE / "data" / "boby2021"
    pts = {n: read_points(data / f"r2000ic_{n}.validation.csv") for n in ("N1", "N2", "N3")}
    return _interleaved(pts) + [("other tool", pts["N2"], [("N1", pts["N1"]), ("N3", pts["N3"])])]


def ur10_splits():
    data = HERE / "data" / "landgraf2021"
    pts = {n: read_points(data / f"ur10_{n}.validation.csv") for n in ("B", "C", "D")}
    return _interleaved(pts) + [("other campaign", pts["C"], [("B", pts["B"]), ("D", pts["D"])])]


def ur5_splits():
    data = HERE / "data" / "jacobi2025"
    grid, rand = (read_points(data / f"ur5_{n}.validation.csv") for n in ("grid", "random"))
    return _interleaved({"grid": grid}) + [("source's split", grid, [("random", rand)])]


#: data set -> (built-in robot, its splits)
DATASETS = {"fanuc": ("r2000ic165f", fanuc_splits), "ur10": ("ur10", ur10_splits), "ur5": ("ur5", ur5_splits)}


def pybotics_python(given: str | None) -> tuple[str | None, str]:
    """An interpreter with pybotics, or None and why not."""
    if given:
        return given, ""
    py = VENV / "bin" / "python"
    if not py.exists():
        try:
            venv.create(VENV, with_pip=True)
            subprocess.run([str(py), "-m", "pip", "install", "-q", "pybotics"], check=True, capture_output=True,
                           timeout=600)
        except (subprocess.SubprocessError, OSError) as e:
            return None, f"could not install pybotics in {VENV}: {e}"
    return str(py), ""


def _mdh_job(robot):
    """The nominal DH rows as pybotics MDH rows: [Rz Tz]_1 [Tx Rx Rz Tz]_2..n, the last Tx Rx in the tool."""
    mdh = [[0.0, 0.0, np.deg2rad(robot.theta_offset_deg[0]), robot.d_mm[0]]]
    for i in range(1, robot.n):
        mdh.append([np.deg2rad(robot.alpha_deg[i - 1]), robot.a_mm[i - 1], np.deg2rad(robot.theta_offset_deg[i]),
                    robot.d_mm[i]])
    last = row_matrix(0.0, 0.0, robot.a_mm[-1], np.deg2rad(robot.alpha_deg[-1]), np.deg2rad(robot.beta_deg[-1]))
    return mdh, last


def _start(robot, pts, last):
    """Base and tool registered on the nominal model: the same start for pybotics as for rodlab."""
    base, tool, _ = register_base_and_tool(robot, ModelParams.nominal(robot, pts.tool_mm), points_observations(pts))
    T = np.eye(4)
    T[:3, 3] = tool
    return {"world": pose_to_matrix(base).tolist(), "tool": (last @ T).tolist(),
            "q": np.deg2rad(pts.q_deg).tolist(), "p": pts.x_W_mm.tolist()}, base, tool


def run_pybotics(python: str, robot, fit, tests) -> dict:
    mdh, last = _mdh_job(robot)
    fit_job, base, tool = _start(robot, fit, last)
    q = np.deg2rad(fit.q_deg[:5])
    check = forward(ModelParams.nominal(robot, tool, base), q).pW
    job = {"mdh": mdh, "world": fit_job["world"], "tool": fit_job["tool"], "fit": fit_job,
           "check": [[a.tolist(), b.tolist()] for a, b in zip(q, check)],
           "tests": {name: _start(robot, t, last)[0] for name, t in tests}}
    res = subprocess.run([python, str(HERE / "pybotics_side.py")], input=json.dumps(job), capture_output=True,
                         text=True, timeout=1200)
    if res.returncode != 0:
        raise RuntimeError(f"pybotics side failed: {res.stderr.strip()[-2000:]}")
    return json.loads(res.stdout)


def diagnosed_joints(robot, fit) -> tuple:
    """The joints whose periodic error ``rodlab diagnose --points`` names on the fit set (the user's workflow:
    diagnose, then calibrate with ``--joint-harmonics``)."""
    from rodlab.app.diagnose.points import diagnose_points
    from rodlab.calibrate.points import identify_points, stated_noise_mm
    pts, noise = stated_noise_mm(fit, None)
    res = identify_points(robot, pts, None, fix_unidentifiable=True)
    found = diagnose_points(robot, pts, res, noise).findings
    return tuple(sorted(int(f.where.split()[-1]) for f in found if f.effect == "periodic_joint_error"))


def run(python: str | None, dataset: str = "fanuc") -> tuple[list, str]:
    name, splits = DATASETS[dataset]
    robot = resolve_robot(name)
    py, why = pybotics_python(python)
    pinned = {f"c_{i + 1}": 0.0 for i in range(robot.n)}
    rows = []
    for protocol, fit, tests in splits():
        full = fit_and_validate(robot, protocol, fit, tests)
        kin = fit_and_validate(robot, protocol, fit, tests, pinned=pinned)
        joints = diagnosed_joints(robot, fit)
        diag = fit_and_validate(robot, protocol, fit, tests, harmonics=joints) if joints else None
        pyb = run_pybotics(py, robot, fit, tests) if py else None
        for k, (name, _) in enumerate(tests):
            other = error_stats(np.array(pyb["tests"][name])) if pyb else None
            rows.append((protocol, name, full[k], kin[k], (joints, diag[k] if diag else None), other))
    return rows, why


def _cell(s) -> str:
    return "-" if s is None else f"{s.mean_mm:.3f} / {s.max_mm:.3f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", choices=[*DATASETS, "all"], default="all")
    ap.add_argument("--python", default=None, help="an interpreter with pybotics installed")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.ERROR)
    for dataset in DATASETS if a.data == "all" else [a.data]:
        t0 = time.perf_counter()
        rows, why = run(a.python, dataset)
        if why:
            print(f"pybotics skipped: {why}", file=sys.stderr)
        print(f"\n{dataset} (robot {DATASETS[dataset][0]}, {time.perf_counter() - t0:.0f} s)\n")
        print("| protocol | validated on | nominal | rodlab | kinematic only | rodlab + diagnosis | pybotics |")
        print("|---|---|---|---|---|---|---|")
        for protocol, name, full, kin, (joints, diag), pyb in rows:
            named = f"{_cell(diag.after)} (J{', J'.join(map(str, joints))})" if diag else "- (none named)"
            print(f"| {protocol} | {name} | {_cell(full.before)} | {_cell(full.after)} | {_cell(kin.after)} | "
                  f"{named} | {_cell(pyb)} |")
    print("\n(mean / max error [mm] on the validation points, base and tool refitted on them)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
