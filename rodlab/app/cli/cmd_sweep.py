"""``rodlab sweep``: L1 x L2 design sweeps (frame, calc or solid model) on Dask."""
from __future__ import annotations

import argparse
import io
import time
from dataclasses import replace
from pathlib import Path

from ...core.design_io import resolve_design
from ...core.enums import FeaModel
from ...core.errors import RodlabError, first_reasons
from ...core.fileio import atomic_write_bytes, atomic_write_text
from ...core.progress import progress as bar_of
from .argtypes import count
from .cadextra import require_mesher
from .reporting import add_report_option, png_file, write_command_report

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("sweep", help="sweep L1 x L2 designs: compliance, c_rod, mass (Dask)",
                       description="Evaluate every L1 x L2 variant of a base design (validated; invalid ones are "
                                   "reported in the table). Results are cached per design, so a re-run only "
                                   "computes what is missing.")
    p.add_argument("--L1", required=True, help="START:STOP:STEP or a,b,c [mm]")
    p.add_argument("--L2", required=True, help="START:STOP:STEP or a,b,c [mm]")
    p.add_argument("--base", default="rod1", help="base design (file or built-in; default rod1)")
    p.add_argument("--model", choices=[m.value for m in FeaModel], default=FeaModel.FRAME.value,
                   help=f"compliance model of every variant (default {FeaModel.FRAME.value})")
    p.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler")
    p.add_argument("--workers", type=count, default=2, help="workers of the local cluster (default 2)")
    p.add_argument("--serial", action="store_true", help="do not use Dask")
    p.add_argument("--calibrate", action="store_true",
                   help="frame: calibrate its joints on one solid FEA run of the family first (the base, or the "
                        "grid's nearest design whose free tubes are long enough; cad extra; ~5-10 s): the joints "
                        "stay the same over L1 x L2, so their measured flexibility carries over; written to "
                        "OUTPUT with .joints.json for --joints")
    p.add_argument("--joints", default=None, metavar="FILE",
                   help="frame: use a stored joint calibration of the family (*.joints.json, from an earlier "
                        "--calibrate or rodlab fea --model solid --joints-out) instead of solving")
    p.add_argument("--cache", default=None, help="cache folder (default: OUTPUT.cache)")
    p.add_argument("--png", default=None, help="heat maps of c_rod and mass: FILE.png, or a folder (it gets "
                                                                  "sweep.png) (default: OUTPUT with .png)")
    p.add_argument("-o", "--output", required=True, help="sweep.csv or sweep.parquet")
    add_report_option(p)
    p.set_defaults(func=cmd_sweep)


def cmd_sweep(args: argparse.Namespace) -> int:
    from rodlab.fea.sweep import parse_range, run_sweep
    from rodlab.fea.sweep_plot import plot_sweep
    base = resolve_design(args.base)
    L1s, L2s = parse_range(args.L1, "L1"), parse_range(args.L2, "L2")
    out = Path(args.output)
    if out.suffix not in (".csv", ".parquet"):
        raise RodlabError(f"output must end in .csv or .parquet, got {out.name!r}")
    mesher = None
    if args.model == "solid":
        geometry = require_mesher()
        mesher = geometry.mesh_rod
    _refuse_if_none_valid(base, L1s, L2s)
    t0 = time.perf_counter()
    calibration, saved = _frame_calibration(args, base, L1s, L2s, out)
    with bar_of(total=len(L1s) * len(L2s), desc=f"sweep ({args.model})", unit="design") as bar:
        def progress(done, total):
            bar.update(done - bar.n)
        df = run_sweep(base, L1s, L2s, model=args.model, scheduler=args.scheduler, workers=args.workers,
                       cache_dir=args.cache or f"{out}.cache", mesher=mesher, use_dask=not args.serial,
                       progress=progress, calibration=calibration)
    _write_table(df, out)
    png = png_file(args.png, "sweep.png") or out.with_suffix(".png")
    label = f"{args.model} model" + (" joint-calibrated on solid FEA" if calibration is not None else "")
    plot_sweep(df, png, title=f"{label}, base design {base.name}", marks={f"base {base.name}": (base.L1_mm, base.L2_mm)})
    _print_summary(df, time.perf_counter() - t0)
    print(f"  wrote {out} and {png}")
    from ..report import FORMAT_SWEEP, Source
    written = [Source(FORMAT_SWEEP, df, out), png] + ([saved] if saved is not None else [])
    if args.report is not None:                 # the base design in 3-D: its frame centreline, weakest load case
        from ..report.views import frame_views
        views = frame_views(base, out.with_name(out.stem + ".base.vtp"), loads="weakest")
        print(f"  wrote {views.fields}" + "".join(f", {p}" for p in views.pngs)
              + (f" (no picture: {views.note})" if views.note else ""))
        written += views.pngs
    write_command_report(args, written, out.parent)
    if not (df["status"] == "ok").any():
        reasons = sorted({str(m) for m in df["message"] if isinstance(m, str) and m})
        raise RodlabError(f"none of the {len(df)} designs is usable ({out} lists each one's reason): "
                          + first_reasons(reasons))
    return 0


def _refuse_if_none_valid(base, L1s, L2s) -> None:
    """Refuse a grid none of whose L1 x L2 designs is a valid rod (lengths in metres, a range below the parts)
    before anything runs or is written, naming the first reasons (a new-user trial: the table and figure of nine
    invalid designs had been written beside an error)."""
    reasons = []
    for L1 in L1s:
        for L2 in L2s:
            try:
                replace(base, L1_mm=float(L1), L2_mm=float(L2))
                return
            except RodlabError as e:
                reasons.append(getattr(e, "detail", str(e)))
    raise RodlabError(f"none of the {len(reasons)} designs of --L1 x --L2 is a valid rod, nothing was run or written: "
                      + first_reasons(dict.fromkeys(reasons)))


def _frame_calibration(args: argparse.Namespace, base, L1s, L2s, out: Path):
    """The frame's joint calibration the sweep uses: read (``--joints``), solved now and saved beside the
    output (``--calibrate``), or none. Returns (calibration or None, the saved file or None)."""
    if (args.calibrate or args.joints) and args.model != "frame":
        raise RodlabError(f"{'--calibrate' if args.calibrate else '--joints'} applies to --model frame")
    if args.calibrate and args.joints:
        raise RodlabError("give --calibrate (solve now) or --joints FILE (stored), not both")
    if args.joints:
        from rodlab.fea.joints_io import read_joints
        calibration = read_joints(args.joints)
        calibration.check_member(base)
        print(f"frame joint-calibrated by {args.joints} (solid FEA of {calibration.base.name})")
        return calibration, None
    if not args.calibrate:
        return None, None
    from rodlab.app.study.family import solid_family_calibration
    from rodlab.fea.joints_io import write_joints

    require_mesher()
    calibration = solid_family_calibration(base, L1s, L2s)
    m1, m2 = calibration.margins_mm
    saved = write_joints(out.with_suffix(".joints.json"), calibration)
    print(f"frame joint-calibrated on the solid FEA of {calibration.base.name} (sections {m1:.1f} / {m2:.1f} mm "
          f"from the ends of the free tubes; span fit residual {100 * calibration.span_residual:.2f} %); "
          f"saved to {saved} (reuse: --joints)")
    return calibration, saved


def _write_table(df, out: Path) -> None:
    """The sweep table as CSV or Parquet (by the suffix), atomically."""
    if out.suffix == ".parquet":
        buf = io.BytesIO()
        try:
            df.to_parquet(buf)
        except ImportError as e:
            raise RodlabError("Parquet needs pyarrow (pip install pyarrow); or write .csv") from e
        atomic_write_bytes(out, buf.getvalue())
    else:
        atomic_write_text(out, df.to_csv(index=False))


def _print_summary(df, seconds: float) -> None:
    ok = df[df["status"] == "ok"]
    print(f"{len(df)} designs ({len(ok)} ok, {len(df) - len(ok)} invalid/failed) in {seconds:.1f} s")
    if len(ok):
        best = ok.loc[ok["c_rod_um"].idxmin()]
        print(f"  stiffest: L1 = {best['L1_mm']:g}, L2 = {best['L2_mm']:g} mm, c_rod = {best['c_rod_um']:.1f} um, "
              f"mass = {1e3 * best['mass_kg']:.0f} g")
    for note in sorted({m for m in ok["message"] if isinstance(m, str) and m}):
        print(f"  note: {note}; rerun with --calibrate (one solid FEA run calibrates the frame's joints for this "
              f"family)")

