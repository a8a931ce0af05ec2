"""``rodlab diagnose``: name the physics that simulation and recordings disagree on."""
from __future__ import annotations

import argparse
import sys

from rodlab.calibrate import read_fixture
from rodlab.calibrate.effects import CAMPAIGN_EFFECTS
from rodlab.calibrate.points import identify_points, stated_noise_mm
from rodlab.stiffness_rig import read_recording
from rodlab.stiffness_rig.effects import RIG_EFFECTS

from ...core.compliance import write_compliance
from ...core.design_io import resolve_design
from ...core.enums import MODEL_FORM
from ...core.errors import RodlabError
from ...core.fileio import atomic_write_json, json_safe
from ...core.units import DEVICE_NOISE_MM
from .argtypes import joint_list, pos_float
from .deviceargs import (add_device_option, campaign_from_args, points_from_args, refuse_rod_slips,
                         warn_flagged_fixture)
from .reporting import add_report_option, default_folder, png_folder, write_command_report
from .columnsargs import add_columns_checked, screen_joint_columns
from .recording_checks import check_recording
from .robotargs import add_robot_options, robot_from_args, robot_help
from .rodargs import compliance_arg, warn_rod_mismatch

__all__ = ["register"]


def register(sub) -> None:
    rig = ", ".join(e.value for e in RIG_EFFECTS)
    campaign = ", ".join(e.value for e in CAMPAIGN_EFFECTS)
    p = sub.add_parser("diagnose", help="locate and explain the mismatch between simulation and recordings",
                       description="Rig: a recording against the simulated compliance of its rod (judged against "
                                   "the design's tolerances and the simulation method's accuracy unless "
                                   "--sim-accuracy exact). Campaign: calibration residuals against the identified "
                                   f"model. Findings use the effect vocabulary (rig: {rig}, {MODEL_FORM}; campaign: "
                                   f"{campaign}; unexplained).")
    p.add_argument("--rig", help="*.rig.csv recording")
    p.add_argument("--sim", help="rig: the simulated compliance file, or a design (rod1: its closed-form compliance)")
    p.add_argument("--campaign", help="*.campaign.csv")
    p.add_argument("--points", help="instrument points (*.validation.csv): calibrate, then test the residuals per "
                                    "joint angle, approach direction, time (time_s) or measurement order, "
                                    "temperature (temp_C) and workspace region")
    p.add_argument("--fixture", help="campaign: *.fixture.json")
    add_device_option(p, prefix="campaign: ", units_also="; rig: diagnose a recording whose r_rod against the "
                      "simulation lies beyond any rod (0.1-10: a units slip or another rod's file is refused)")
    add_robot_options(p, help="campaign / points: " + robot_help())
    p.add_argument("--design", help="rig: the *.rod.toml design (joint places, tolerances; default: the design the "
                                    "--sim file was made from, if it is still there)")
    p.add_argument("--rod", help="campaign: the *.compliance.json used (as in `rodlab calibrate`; a design for its "
                                 "calc compliance)")
    p.add_argument("--sim-accuracy", type=sim_accuracy, default=None, metavar="ACC",
                   help="rig: what the simulation is worth. Default: the design's tolerances ([tolerances] of the "
                        "design file over documented defaults) and the simulation method's accuracy; a measured "
                        "file: 1 %% per entry. `exact`: the simulation is the rod (a re-check against an earlier "
                        "measurement); a number such as 0.05: that relative accuracy per C_F entry in place of the "
                        "method's, the design's tolerances kept where the design is known")
    p.add_argument("--validate", help="campaign: validation points, to show the positioning error improve")
    p.add_argument("--noise-um", type=pos_float, default=None,
                   help="campaign: device noise [um] (default 3); points: the instrument's noise per coordinate "
                        "(default: the file's sigma_*_mm columns, else 25, a laser tracker)")
    p.add_argument("--json", help="write the contract's diagnosis report")
    p.add_argument("--png", type=png_folder, help="folder for figures (each under its own name)")
    p.add_argument("--export", help="rig: write the corrected compliance (the model with the found physics)")
    p.add_argument("--joint-harmonics", type=joint_list, default=(), metavar="LIST",
                   help="points / campaign: joints whose periodic errors the calibration already identifies (as "
                        "`rodlab calibrate --joint-harmonics`); they are modelled, not suspects")
    add_columns_checked(p)
    add_report_option(p)
    p.set_defaults(func=cmd_diagnose)


def sim_accuracy(text: str):
    """``--sim-accuracy``: ``exact``, ``design`` or a relative accuracy in (0, 1]."""
    word = text.strip().lower()
    if word in ("exact", "design"):
        return word
    try:
        value = float(word.rstrip("%")) / (100.0 if word.endswith("%") else 1.0)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected exact, design or a relative accuracy such as 0.05 or 5%, got "
                                         f"{text!r}") from None
    if not 0 < value <= 1:
        raise argparse.ArgumentTypeError(f"a relative accuracy lies in (0, 1] (0.05 = 5 %), got {text!r}")
    return value


def cmd_diagnose(args: argparse.Namespace) -> int:
    _check_modes(args)
    if args.points:
        return _diagnose_points(args)
    written: list = []
    diag = _diagnose_rig(args, written) if args.rig else _diagnose_campaign(args, written)
    if args.json:
        written.insert(0, diag.write(args.json))
        print(f"wrote {written[0]}")
    else:
        from ..report import Source
        report = diag.to_dict()
        written.insert(0, Source(report["format"], report))
    write_command_report(args, written, default_folder(args))
    return 0


def _check_modes(args: argparse.Namespace) -> None:
    """One of --rig, --campaign, --points, with only the options that apply to it."""
    if args.rig and args.joint_harmonics:
        raise RodlabError("--joint-harmonics is for --points or --campaign (a robot's joints); a rig recording has "
                          "none: leave it out")
    if sum(bool(x) for x in (args.rig, args.campaign, args.points)) != 1:
        raise RodlabError("give one of --rig REC.rig.csv --sim SIM.compliance.json, --campaign C.csv --fixture F.json "
                          "--rod ROD.compliance.json, or --points P.validation.csv --robot ROBOT")
    if args.sim_accuracy is not None and not args.rig:
        raise RodlabError("--sim-accuracy is what a rig recording's simulation is worth (with --rig); a campaign's "
                          "rod file is weighed by its own method: leave it out")
    if args.rig and not args.sim:
        raise RodlabError("--rig needs --sim SIM.compliance.json")
    if args.campaign and args.design:
        raise RodlabError("--design is the rig's design (with --rig); a campaign takes the rod's compliance file "
                          "as --rod ROD.compliance.json")
    if args.campaign and not (args.fixture and args.rod):
        points = str(args.campaign).endswith((".validation.csv", ".points.csv"))
        raise RodlabError("--campaign needs --fixture F.json and --rod ROD.compliance.json"
                          + (f"; {args.campaign} looks like an instrument's points: diagnose it with --points "
                             f"{args.campaign}" if points else " (or --points for an instrument's points)"))


def _diagnose_rig(args: argparse.Namespace, written: list):
    """``--rig REC --sim SIM``: the recording diagnosed against its simulation; figures and the corrected file
    appended to ``written``."""
    sim = compliance_arg(args.sim)
    design = resolve_design(args.design) if _rig_design(args) else None
    rec = read_recording(args.rig)
    warn_rod_mismatch(rec.rod, sim.rod, args.rig)
    check_recording(rec, sim, getattr(args, "units_checked", False))
    from ..diagnose import diagnose_rig
    diag, model = diagnose_rig(rec, sim, design, accuracy=args.sim_accuracy)
    print(diag.summary())
    if args.png:
        from ..diagnose.plots import plot_rig_diagnosis
        for p in plot_rig_diagnosis(model, args.png, diag, rec.rod):
            written.append(p)
            print(f"wrote {p}")
    if args.export:
        from ..diagnose import corrected_compliance
        corrected = corrected_compliance(sim, diag, model, rec.loaded_axes(), args.rig, design)
        for w in corrected.provenance["warnings"]:
            print(f"warning: {args.export}: {w}", file=sys.stderr)
        written.append(write_compliance(corrected, args.export))
        print(f"wrote {written[-1]}")
    return diag


def _diagnose_campaign(args: argparse.Namespace, written: list):
    """``--campaign C --fixture F --rod ROD``: the campaign diagnosed (and validated with ``--validate``); figures
    appended to ``written``."""
    robot = robot_from_args(args)
    noise_mm = args.noise_um * 1e-3 if args.noise_um else DEVICE_NOISE_MM
    pts = points_from_args(args, args.validate, robot) if args.validate else None
    fix = read_fixture(args.fixture)
    warn_flagged_fixture(fix, args.fixture)
    from ..diagnose import diagnose_campaign
    rod = compliance_arg(args.rod, slips_refused=True)
    refuse_rod_slips(rod, args.rod, args)
    diag, fits = diagnose_campaign(robot, campaign_from_args(args, robot), fix,
                                   rod, noise_mm, pts, harmonics=args.joint_harmonics,
                                   columns_checked=args.columns_checked)
    print(diag.summary())
    if "validation" in diag.extra:
        v = diag.extra["validation"]
        print(f"  validation mean / max [mm]: nominal {v['nominal']['mean_mm']:.3f} / {v['nominal']['max_mm']:.3f}, "
              f"calibrated {v['before']['mean_mm']:.3f} / {v['before']['max_mm']:.3f}, with the found physics "
              f"{v['after']['mean_mm']:.3f} / {v['after']['max_mm']:.3f}")
    if args.png:
        from ..diagnose.plots import plot_campaign_diagnosis
        for p in plot_campaign_diagnosis(diag, fits, args.png, noise_mm):
            written.append(p)
            print(f"wrote {p}")
    return diag


def _rig_design(args) -> str | None:
    """``--design``; ``--rod`` with ``--rig`` is its old spelling (it named the design there but the compliance file
    everywhere else): still read, with a deprecation warning."""
    if args.rod and args.design:
        raise RodlabError("--rod with --rig is the old spelling of --design; give --design only")
    if args.rod:
        print(f"warning: --rod with --rig is deprecated (--rod is a compliance file in calibrate and diagnose "
              f"--campaign); the rig's design is --design: --design {args.rod}", file=sys.stderr)
        args.design, args.rod = args.rod, None
    return args.design


def _diagnose_points(args) -> int:
    """Instrument points: the calibration of ``calibrate --points``, then its residuals explained."""
    from ..diagnose.points import diagnose_points
    robot = robot_from_args(args)
    pts = points_from_args(args, args.points, robot)
    pts, noise_mm = stated_noise_mm(pts, args.noise_um * 1e-3 if args.noise_um else None)
    screen_joint_columns(args, robot, pts, args.points, noise_mm, "diagnosed")
    res = identify_points(robot, pts, noise_mm, fix_unidentifiable=True,
                          harmonics=args.joint_harmonics)
    diag = diagnose_points(robot, pts, res, noise_mm)
    print(diag.summary())
    report = json_safe(diag.to_dict())
    if args.json:
        written = [atomic_write_json(args.json, report)]
        print(f"wrote {written[-1]}")
    else:
        from ..report import Source
        written = [Source(report["format"], report)]
    write_command_report(args, written, default_folder(args))
    return 0
