"""Benchmark: `rodlab fea rod1 --model solid` as a user runs it (defaults: the recovery error estimate, imports
included, a fresh process; first with an empty mesh cache, then again with the mesh cached, as a rerun of the
same design finds it) against CalculiX on the same mesh (the command's default half mesh mirrored into the
whole rod: the same discretisation), alternated so that both see the same machine.

    python benchmarks/fea_vs_calculix.py [ROUNDS] [SIZE_MM ...]   # docs/benchmarks/fea_vs_calculix.md (~2-6 min)

Without sizes the command's default mesh; each SIZE_MM adds rows at that element size (``--size``) as well.

Goal (issue 47): the command at least 8x faster than CalculiX on the same mesh. CalculiX solves the three force
cases (C_F only, three ``*STEP``s, ``OMP_NUM_THREADS=2``); the command solves six load cases (C_F and C_g) and
estimates its error from that solve. Only CalculiX's run is timed (its deck written from
the mesh, ccx, its output read), not the meshing that precedes it.
"""
from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_fea import machine_check  # noqa: E402  (the same fixed workload as fea.md's)
from pages import user_env, write_page  # noqa: E402
OUT = ROOT / "docs" / "benchmarks" / "fea_vs_calculix.md"

_CCX = r"""
import json, sys, time
from rodlab import resolve_design
from rodlab.fea.compute import DEFAULT_GRADING, default_solid_size_mm
from rodlab.fea.calculix import run_ccx_compliance
from rodlab.geometry import mesh_rod
d = resolve_design("rod1")
size = float(sys.argv[1]) if len(sys.argv) > 1 else default_solid_size_mm(d)
half = mesh_rod(d, size_mm=size, grading=DEFAULT_GRADING, half=True)
whole = half.mirrored()
t0 = time.perf_counter(); C = run_ccx_compliance(d, whole); t = time.perf_counter() - t0
print(json.dumps({"t_ccx_s": t, "nodes": int(whole.mesh.p.shape[1]), "C_F": C.tolist(), "size_mm": size}))
"""


def _cli_seconds(tmp: Path, size: float | None, cache: Path) -> tuple[float, list]:
    """Wall time of the command in a fresh process (mesh cache folder ``cache``), and its C_F."""
    out = tmp / "rod1.fea.json"
    extra = [] if size is None else ["--size", f"{size:g}"]
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "rodlab", "-q", "fea", "rod1", "--model", "solid", *extra, "-o", str(out)],
                   check=True, capture_output=True, text=True, env=user_env(RODLAB_CACHE_DIR=str(cache)))
    wall = time.perf_counter() - t0
    return wall, json.loads(out.read_text())["C_F_mm_per_N"]


def _ccx_run(size: float | None) -> dict:
    args = [] if size is None else [f"{size:g}"]
    r = subprocess.run([sys.executable, "-c", _CCX, *args], check=True, capture_output=True, text=True,
                       env=dict(os.environ, PYTHONWARNINGS="ignore"))
    return json.loads(r.stdout.strip().splitlines()[-1])


def main(rounds: int = 2, sizes: tuple = ()) -> int:
    from rodlab.fea.calculix import ccx_available
    if ccx_available() is None:
        raise SystemExit("CalculiX (ccx) is not installed: apt-get install calculix-ccx")
    import numpy as np
    check0 = machine_check()
    rows, ratios, warm_ratios = [], {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for size in (None, *sizes):
            for i in range(rounds):
                cache = Path(tmp) / f"cache-{size}-{i}"                # empty: the first run meshes
                cli, C_ours = _cli_seconds(Path(tmp), size, cache)
                ccx = _ccx_run(size)
                warm, _ = _cli_seconds(Path(tmp), size, cache)         # the rerun finds the mesh
                C_ours, C_ccx = np.array(C_ours), np.array(ccx["C_F"])
                big = np.abs(C_ours) > 1e-3 * np.abs(C_ours).max()
                diff = float(np.max(np.abs(C_ccx[big] / C_ours[big] - 1)))
                ratios.setdefault(ccx["size_mm"], []).append(ccx["t_ccx_s"] / cli)
                warm_ratios.setdefault(ccx["size_mm"], []).append(ccx["t_ccx_s"] / warm)
                label = "default" if size is None else f"--size {size:g}"
                rows.append(f"| {label} ({ccx['size_mm']:g} mm, {ccx['nodes']} nodes whole) | {i + 1} | {cli:.2f} | "
                            f"{warm:.2f} | {ccx['t_ccx_s']:.1f} | {ratios[ccx['size_mm']][-1]:.1f}x | "
                            f"{warm_ratios[ccx['size_mm']][-1]:.1f}x | {100 * diff:.3f} % |")
                print(rows[-1], flush=True)
    check1 = machine_check()
    lines = ["# `rodlab fea rod1 --model solid` against CalculiX on the same mesh", "",
             f"`python benchmarks/fea_vs_calculix.py {rounds}` on {platform.machine()}, {os.cpu_count()} cores, "
             f"Python {platform.python_version()}, {time.strftime('%Y-%m-%d')}. The command as a user runs it "
             "(defaults: six load cases on the half mesh and the recovery error estimate from that solve; a fresh "
             "process, imports included; first with an empty cache, then rerun with the mesh and its assembly plan "
             "cached) against "
             "CalculiX 2 threads on the whole mesh the half one mirrors into (three force cases, C_F only; its deck, "
             "run and output timed, not the meshing), alternated.", "",
             "| mesh | round | `rodlab fea rod1 --model solid` [s] | rerun, mesh and plan cached [s] | CalculiX [s] | "
             "CalculiX / rodlab | CalculiX / rerun | C_F difference |",
             "|---|---|---:|---:|---:|---:|---:|---:|", *rows, "",
             "Median ratio " + ", ".join(f"**{float(np.median(r)):.1f}x** at {s:g} mm" for s, r in ratios.items())
             + "; rerun " + ", ".join(f"**{float(np.median(r)):.1f}x** at {s:g} mm" for s, r in warm_ratios.items())
             + " (goal >= 8x). Machine check (20 Cholesky "
             f"factorisations of 1500 x 1500): {check0:.2f} s before, {check1:.2f} s after (1.8 s on a quiet VM)."]
    write_page(OUT, lines, ROOT / "benchmarks" / "fea_vs_calculix_notes.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(int(sys.argv[1]) if len(sys.argv) > 1 else 2, tuple(float(v) for v in sys.argv[2:])))
