"""``rodlab study``: from rod designs to the calibration accuracy each will give on a robot."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from rodlab.calibrate import read_fixture

from ...core.design_io import resolve_design
from ...core.errors import RodlabError, first_reasons
from ...core.progress import progress as bar_of
from ...core.units import PAPER_R_ROD, PAPER_ROD_SLIP
from .argtypes import base_pose, count, nonneg_float, pos_float, seed
from .reporting import add_report_option, write_command_report
from .robotargs import add_robot_options, robot_from_args

__all__ = ["register"]

_METHODS = ("none", "calc", "fea", "meas")


def register(sub) -> None:
    p = sub.add_parser(
        "study", help="predict each rod design's calibration accuracy on a robot (band, budget, Pareto)",
        description="For every design (an L1 x L2 grid around one base, with tube-material and tube-size variants, "
                    "or a list of designs): compliance (the frame, joint-calibrated on one solid FEA run per family), "
                    "mass, c_rod, thermal growth, natural frequencies, strength margins; pose planning on the robot "
                    "(O1..O5); then the predicted accuracy per compensation method with its 90 % band and error "
                    "budget: by default from the planned campaign's linearised identification (seconds per design); "
                    "with --monte-carlo from N simulated MultiCal campaigns, each calibrated with every method and "
                    "validated. Writes study.csv, pareto.png, heatmaps.png (grids), study.html and study.json into "
                    "OUTPUT; prints a recommendation. Cached per design (and replicate): a re-run resumes.")
    p.add_argument("designs", nargs="+", help="*.rod.toml files or built-in names (rod1 .. rod6); with --L1/--L2 "
                                              "one base design")
    p.add_argument("--L1", default=None, help="START:STOP:STEP or a,b,c [mm] (a grid around the base)")
    p.add_argument("--L2", default=None, help="START:STOP:STEP or a,b,c [mm]")
    p.add_argument("--materials", default=None, help="tube-material variants of the base, e.g. cfrp,steel_304")
    p.add_argument("--tubes", default=None, help="tube-size variants of the base, OUTERxWALL [mm], e.g. 25x2,30x1.5")
    add_robot_options(p)
    p.add_argument("--fixture", default=None,
                   help="*.fixture.json of the clamping positions (default: the simulator's five positions around "
                        "{W}, 650 mm in front of the robot)")
    _add_layout_options(p)
    p.add_argument("--monte-carlo", action="store_true",
                   help="simulate and calibrate --replicates campaigns per design instead of the linear predictor")
    p.add_argument("--replicates", type=count, default=20,
                   help="with --monte-carlo: simulated campaigns per design (default 20)")
    p.add_argument("--draws", type=count, default=256,
                   help="linear predictor: draws of r_rod, the compliance's shape and the validation sets (default 256)")
    p.add_argument("--methods", default=",".join(_METHODS), help="compensation methods (default none,calc,fea,meas)")
    p.add_argument("--orientations", type=count, default=6, help="rod orientations per clamping position (default 6)")
    p.add_argument("--seed", type=seed, default=0, help="first replicate's seed (the same draws for every design)")
    p.add_argument("--r-prior-metal", default="1.01:1.05", metavar="LOW:HIGH",
                   help="true/simulated compliance of metal rods (paper: 1.01-1.05)")
    p.add_argument("--r-prior-composite", default="1.23:2.30", metavar="LOW:HIGH",
                   help="the same for carbon (anisotropic) tubes (paper: 1.23-2.30)")
    p.add_argument("--shape-sigma", type=nonneg_float, default=0.05,
                   help="how far the true compliance's shape departs from the model's (default 0.05)")
    p.add_argument("--meas-sigma", type=nonneg_float, default=0.01, help="the rig measurement's relative uncertainty")
    p.add_argument("--error-scale", type=nonneg_float, default=1.0, help="robot kinematic errors (1 = ~0.5 mm, 0.05 deg)")
    p.add_argument("--device-noise", type=nonneg_float, default=0.003, help="MultiCal device noise, 1 sigma [mm]")
    p.add_argument("--instrument-noise", type=nonneg_float, default=0.02, help="validation instrument noise, 1 sigma [mm]")
    p.add_argument("--robot-floor-mm", type=nonneg_float, default=0.0,
                   help="the robot's own unmodelled error: smooth joint-angle errors whose mean on rigid-tool "
                        "validation is this [mm] (paper, TX90 by laser scanner: 0.263; default 0 = none)")
    p.add_argument("--rod-slip", type=nonneg_float, default=PAPER_ROD_SLIP,
                   help="the rod's non-repeatable deflection (slip, hysteresis in its joints; no compensation removes "
                        "it): at every point the deflection under this many times its own weight in a random "
                        f"direction (default {PAPER_ROD_SLIP:g}, fitted to the paper's Table 3; 0 = elastic)")
    p.add_argument("--no-budget", action="store_true",
                   help="with --monte-carlo: skip the error budget (one fit fewer per replicate)")
    p.add_argument("--no-calibrate", action="store_true",
                   help="use the frame's global calibration instead of one solid FEA run per design family")
    p.add_argument("--scheduler", default=None, help="address of an existing Dask scheduler")
    p.add_argument("--workers", type=count, default=2, help="workers of the local cluster (default 2)")
    p.add_argument("--serial", action="store_true", help="do not use Dask")
    p.add_argument("--cache", default=None, help="cache folder (default OUTPUT/cache)")
    p.add_argument("-o", "--output", required=True, help="output folder")
    add_report_option(p)
    p.set_defaults(func=cmd_study)


def _range2(text: str, name: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in text.split(":"))
    except ValueError:
        raise RodlabError(f"--{name} {text!r}: expected LOW:HIGH, e.g. 1.01:1.05") from None
    if not (0.1 <= lo <= hi <= 10):
        raise RodlabError(f"--{name} {text!r}: expected 0.1 <= LOW <= HIGH <= 10")
    if lo < PAPER_R_ROD[0] - 0.05 or hi > PAPER_R_ROD[1] + 0.05:      # a paper trial: 0.8 and 3.5 passed unremarked
        stiffer = "; below 1 a rod stiffer than its simulation, which none of them was" if lo < 1.0 else ""
        print(f"warning: --{name} {text}: beyond the paper's measured rods (r_rod {PAPER_R_ROD[0]:.2f}-"
              f"{PAPER_R_ROD[1]:.2f}){stiffer}; the rod slip (--rod-slip) was fitted on rods within that range, so its "
              "share is an extrapolation there", file=sys.stderr)
    return lo, hi


def _methods(text: str) -> tuple:
    ms = tuple(m.strip().lower() for m in text.split(",") if m.strip())
    bad = [m for m in ms if m not in _METHODS]
    if bad or not ms:
        raise RodlabError(f"--methods {text!r}: expected a comma list of {', '.join(_METHODS)}")
    return ms


def _read_designs(names: list[str]) -> list:
    """Every design named (a file or a built-in), or one error listing each that cannot be read."""
    designs, bad = [], []
    for name in names:
        try:
            designs.append(resolve_design(name))
        except RodlabError as e:
            bad.append((name, e))
    if len(bad) == 1:
        raise bad[0][1]
    if bad:                                                             # one line, each file named in it
        raise RodlabError(f"{len(bad)} of {len(names)} designs cannot be read (`rodlab validate` lists every problem "
                          "of each): " + "; ".join(str(e) if name in str(e) else f"{name}: {e}" for name, e in bad))
    return designs


def _lengths_mm(values, name: str, given: str) -> list:
    """``--L1`` / ``--L2`` values [mm]; all below 10 mm is a range in metres (no rod's tube is that short)."""
    if max(values) < 10.0:
        raise RodlabError(f"--{name} {given}: lengths are millimetres, and every value is below 10 mm: did you give "
                          f"metres? ({max(values):g} m = {1000 * max(values):g} mm): multiply by 1000")
    return values


def _candidates(args):
    from rodlab.app.study.designs import check_variants, grid_candidates, list_candidates, parse_tube
    from rodlab.fea.sweep import parse_range
    grid = args.L1 is not None or args.L2 is not None or args.materials or args.tubes
    if not grid:
        return list_candidates(_read_designs(args.designs)), None
    if len(args.designs) != 1:
        raise RodlabError("--L1/--L2/--materials/--tubes vary one base design; give exactly one")
    base = resolve_design(args.designs[0])
    L1s = _lengths_mm(parse_range(args.L1, "L1"), "L1", args.L1) if args.L1 else [base.L1_mm]
    L2s = _lengths_mm(parse_range(args.L2, "L2"), "L2", args.L2) if args.L2 else [base.L2_mm]
    mats = [m.strip() for m in args.materials.split(",")] if args.materials else [None]
    tubes = [parse_tube(t) for t in args.tubes.split(",")] if args.tubes else [None]
    check_variants(base, mats, tubes, L1s, L2s)
    return grid_candidates(base, L1s, L2s, mats, tubes), (L1s, L2s)


#: the largest rod slip a study takes (4x the paper's fit): past ~10-50 the scatter makes every weak parameter fall
#: to its prior and the predicted error tends back to the nominal model's, not up with the slip
MAX_ROD_SLIP = 10.0


def _check_numbers(args) -> None:
    for name in ("replicates", "orientations", "workers", "draws"):
        if getattr(args, name) < 1:
            raise RodlabError(f"--{name} must be >= 1, got {getattr(args, name)}")
    if args.orientations < 2:
        raise RodlabError("--orientations must be >= 2 (the rod's orientations at a clamping position)")
    if args.rod_slip > MAX_ROD_SLIP:
        raise RodlabError(f"--rod-slip {args.rod_slip:g}: expected 0-{MAX_ROD_SLIP:g} (the rod's non-repeatable "
                          f"deflection in multiples of its own weight; the paper's rods: {PAPER_ROD_SLIP:g}); beyond that "
                          "the identification's priors hold the robot at its nominal model and the prediction stops "
                          "growing with the slip (it fell again from 50 to 1000)")


def _assumptions(args, cands=()) -> str:
    """What the prediction assumes beyond the designs, with the options that change it (the study's page and
    console show it: a designer must see why one design beats another)."""
    from rodlab.app.study.designs import R_PRIOR_AS_BUILT, is_as_built
    built = [c.label for c in cands if c.design is not None and is_as_built(c.design)]
    as_built = (f"; {', '.join(built)}: written by `rodlab update` from a measurement, r_rod "
                f"{R_PRIOR_AS_BUILT[0]:g}:{R_PRIOR_AS_BUILT[1]:g} (the measurement is in it)") if built else ""
    return (f"the rod as built is r_rod x its simulation, r_rod uniform in {args.r_prior_metal} for metal tubes and "
            f"{args.r_prior_composite} for carbon ones (the paper's measured rods; --r-prior-metal, "
            f"--r-prior-composite: narrow it for a laminate you have coupon-tested){as_built}; the rod's non-repeatable "
            f"deflection (slip, hysteresis in its joints) {args.rod_slip:g} x its deflection under its own weight "
            f"(--rod-slip; 0: none); the robot's own unmodelled error {args.robot_floor_mm:g} mm (--robot-floor-mm); "
            f"device noise {args.device_noise * 1e3:g} um, validation instrument {args.instrument_noise * 1e3:g} um; "
            f"the compliance's shape {args.shape_sigma:g} and the rig's measurement {args.meas_sigma:g} uncertain "
            "(relative, 1 sigma)")


def _print_unusable(table) -> None:
    """Every design the study could not use (invalid, unreachable, failed), with its reason (study.csv too), and
    every usable one's note."""
    from rodlab.app.study.report import has_message
    designs = table.drop_duplicates("design")
    bad = designs[designs["status"] != "ok"]
    if len(bad):
        print(f"{len(bad)} of {len(designs)} designs not usable:")
    for r in bad.itertuples():
        print(f"  {r.design}: {r.status}: {r.message}")
    for r in designs[designs["status"] == "ok"].itertuples():
        if has_message(r.message):
            print(f"note: {r.design}: {r.message}")


def _add_layout_options(p) -> None:
    """--fixture-distance-mm and --base: where the clamping positions are relative to the robot."""
    where = p.add_mutually_exclusive_group()
    where.add_argument("--fixture-distance-mm", type=pos_float, default=None, metavar="D",
                       help="the clamping positions' centre {W} D mm in front of the robot base, 250 mm up (default "
                            "650): a rod that cannot reach them is reported unreachable")
    where.add_argument("--base", type=base_pose, default=None, metavar="X,Y,Z,A,B,C",
                       help="the robot base {0} in {W} [mm, deg], as `rodlab plan --base` takes it (write "
                            "--base=-700,0,... when X is negative)")


def _base(args) -> tuple | None:
    """The robot base {0} in {W} [mm, deg] from --base or --fixture-distance-mm; None: the standard layout."""
    from rodlab.calibrate.setup_layout import standard_base
    if args.base is not None:
        return tuple(float(v) for v in args.base)
    if args.fixture_distance_mm is not None:
        return tuple(float(v) for v in standard_base(args.fixture_distance_mm))
    return None


def _layout(args) -> str:
    if args.base is not None:
        return "robot base {0} in {W} at " + ",".join(f"{v:g}" for v in args.base) + " (--base)"
    distance = 650.0 if args.fixture_distance_mm is None else args.fixture_distance_mm
    return f"{{W}} {distance:g} mm in front of the robot base, 250 mm up" + (
        " (--fixture-distance-mm)" if args.fixture_distance_mm is not None else " (the standard layout)")


def cmd_study(args: argparse.Namespace) -> int:
    from rodlab.app.study import StudySpec, run_study, write_study_outputs
    from rodlab.app.study.design_warnings import warning_lines
    from rodlab.app.study.family import family_joints
    from rodlab.calibrate.predict import Priors
    from rodlab.calibrate.simulate import standard_fixture

    _check_numbers(args)
    methods = _methods(args.methods)
    robot = robot_from_args(args)
    fixture = read_fixture(args.fixture) if args.fixture else standard_fixture()
    priors = Priors(error_scale=args.error_scale, device_noise_mm=args.device_noise,
                    instrument_noise_mm=args.instrument_noise, shape_sigma=args.shape_sigma,
                    meas_sigma=args.meas_sigma, robot_floor_mm=args.robot_floor_mm,
                    rod_slip=args.rod_slip)
    spec = StudySpec(methods, args.replicates, args.orientations, priors, _range2(args.r_prior_metal, "r-prior-metal"),
                     _range2(args.r_prior_composite, "r-prior-composite"), args.seed, not args.no_budget,
                     args.monte_carlo, args.draws, _base(args))
    cands, grid = _candidates(args)
    if not any(c.design is not None for c in cands):
        raise RodlabError(f"none of the {len(cands)} designs is a valid rod, nothing was run or written: "
                          + first_reasons(dict.fromkeys(c.invalid for c in cands)))
    out = Path(args.output)
    t0 = time.perf_counter()
    cache = Path(args.cache) if args.cache else out / "cache"
    joints, model_note = family_joints(cands, grid is not None, not args.no_calibrate, cache)
    how = (f"{args.replicates} simulated campaigns (Monte Carlo)" if args.monte_carlo
           else f"linear predictor ({args.draws} draws)")
    print(f"{len(cands)} designs on {robot.name}, {how} x {len(methods)} methods; compliance: {model_note}; "
          f"layout: {_layout(args)}")
    tasks = len(cands) * (1 + args.replicates) if args.monte_carlo else len(cands)
    with bar_of(total=tasks, desc="study", unit="task" if args.monte_carlo else "design") as bar:
        run = run_study(cands, robot, fixture, spec, joints, cache, args.scheduler,
                        args.workers, not args.serial, lambda done, total: bar.update(done - bar.n))
    elapsed = time.perf_counter() - t0
    header = {"robot": robot.name, "fixture": args.fixture or "simulator's five positions (standard_fixture)",
              "layout": _layout(args),
              "designs": len(cands), "predictor": how, "methods": ", ".join(methods),
              "compliance": model_note, "assumptions": _assumptions(args, cands), "time": f"{elapsed:.0f} s"}
    res = write_study_outputs(out, run, robot.name, grid is not None, header,
                              {"fixture": args.fixture, "compliance": model_note, "elapsed_s": elapsed},
                              designs={c.label: c.design for c in cands})
    _print_unusable(res.table)
    print(f"assumptions (each an option): {_assumptions(args, cands)}")
    for line in warning_lines(res.warnings):
        print(f"warning: {line}")
    print(f"recommendation: {res.recommendation.text}")
    print(f"  wrote {', '.join(res.files)} in {out} ({elapsed:.0f} s)")
    write_command_report(args, [out / f for f in res.files if f.endswith((".json", ".png"))], out)
    designs = res.table.drop_duplicates("design")
    if not (designs["status"] == "ok").any():     # a result, not an input error (those are refused up front)
        print(f"no design is usable: none of the {len(designs)} designs (listed above, and in {out / 'study.csv'})",
              file=sys.stderr)
        return 3
    return 0
