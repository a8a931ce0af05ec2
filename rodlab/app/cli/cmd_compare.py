"""``rodlab compare``: calibrate one campaign with every compensation method (the paper's Table 3)."""
from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

from rodlab.calibrate import RodDeflection, read_fixture
from rodlab.calibrate.crossval import Prediction

from ...core.compliance import read_compliance
from ...core.errors import RodlabError
from ...core.fileio import atomic_write_json, json_safe
from .calibrateargs import add_identify_options
from .calibration_run import run_calibration, stated_noise_reason
from .deviceargs import add_device_option, campaign_from_args, refuse_rod_slips, warn_flagged_fixture
from .reporting import default_folder, write_command_report
from .robotargs import robot_from_args
from .verdict import judge

__all__ = ["register", "cmd_compare"]

log = logging.getLogger(__name__)


def register(sub) -> None:
    p = sub.add_parser("compare", help="run every compensation method on one campaign (the paper's Table 3)",
                       description="Calibrate one campaign with several compliance files (and with none, always added) "
                                   "and print the validation statistics in the layout of the paper's Table 3.")
    p.add_argument("campaign")
    p.add_argument("--fixture", required=True, help="*.fixture.json (clamping poses, contact force)")
    add_device_option(p)
    p.add_argument("--rod", action="append", required=True, metavar="LABEL=FILE",
                   help="a compliance file per method, e.g. calc=rod1.calc.json fea=rod1.fea.json (repeatable)")
    p.add_argument("--png", default=None, help="the error distributions per method (the paper's Fig. 10): FILE.png, "
                                               "or a folder (it gets error_distributions.png)")
    p.add_argument("--json", default=None, help="write the table (format rodlab.comparison/1, docs/formats.md)")
    add_identify_options(p)
    p.set_defaults(func=cmd_compare)


def _compare_runs(items, args) -> list:
    """(name, rod file, compensation) per ``--rod LABEL=FILE``, led by no compensation; checked before any run.
    A label is only a name: the file's matrices compensate whatever it is called (a file of method ``none``
    compensates nothing, and says so)."""
    runs = []
    for item in items:
        label, eq, path = item.partition("=")
        if not eq or not label.strip() or not path.strip():
            raise RodlabError(f"--rod {item!r}: expected LABEL=FILE (e.g. fea=rod1.fea.compliance.json)")
        if path.strip().lower() == "none":
            raise RodlabError(f"--rod {item!r}: compare runs the uncompensated calibration itself (the 'None' row): "
                              "leave it out and give the compliance files to compare with it")
        rod = read_compliance(path, warn_unit_slips=False)
        refuse_rod_slips(rod, item, args)
        if not runs:
            runs.append(("None", rod, RodDeflection.of(None)))
        if label.strip().lower() == "none" and rod.method.value != "none":
            raise RodlabError(f"--rod {item!r}: the label 'none' is the uncompensated run, which compare adds "
                              f"itself, but {path} is a {rod.method} file; label it by its method "
                              f"(e.g. {rod.method}={path})")
        if rod.method.value == "none":
            log.warning("--rod %s: a method-none file compensates nothing", item)
        runs.append((label.strip(), rod, RodDeflection.of(rod, label.strip())))
    return runs


def cmd_compare(args: argparse.Namespace) -> int:
    args.robot = args.robot or "tx90"
    if not args.validate:
        raise RodlabError("compare needs --validate FILE (the statistics come from the validation points); add the "
                          "campaign's *.validation.csv")
    planned = _compare_runs(args.rod, args)
    camp = campaign_from_args(args, robot_from_args(args))
    warn_flagged_fixture(read_fixture(args.fixture), args.fixture)
    runs = [(name, run_calibration(args, rod, comp, camp)) for name, rod, comp in planned]
    for _, run in runs:                  # the verdict of `rodlab calibrate`: its own reasons and the validation's
        judge(run.result, Prediction.of_validation(run.calibrated_mm, run.nominal_mm, run.result.rms_mm))
        noisy = stated_noise_reason(run, args)
        if noisy is not None:
            run.result.warnings.append(noisy)
    w = max([10, *(len(name) for name, _ in runs)])        # long --rod labels keep the columns aligned
    print(f"{'method':<{w}} {'Mean/[mm]':>10} {'Max/[mm]':>10} {'Median/[mm]':>12} {'SD/[mm]':>9} {'fit rms um':>11} "
          f"{'trusted':>8}")
    before = runs[0][1].before
    print(f"{'nominal':<{w}} {before.mean_mm:10.3f} {before.max_mm:10.3f} {before.median_mm:12.3f} {before.sd_mm:9.3f}")
    for name, run in runs:
        after = run.after
        print(f"{name:<{w}} {after.mean_mm:10.3f} {after.max_mm:10.3f} {after.median_mm:12.3f} {after.sd_mm:9.3f} "
              f"{run.result.rms_mm * 1e3:11.2f} {'yes' if not run.result.warnings else 'NO':>8}")
    untrusted = [name for name, run in runs if run.result.warnings]
    if untrusted:
        print(f"NOT TRUSTED: {', '.join(untrusted)} (`rodlab calibrate` with that compensation says why; "
              "`rodlab diagnose --campaign` finds what is missing)", file=sys.stderr)
    written = _write_comparison(args, runs)
    if args.png:
        from rodlab.calibrate.plots import plot_error_distributions
        errors = {"nominal": runs[0][1].nominal_mm} | {name: run.calibrated_mm for name, run in runs}
        written.append(plot_error_distributions(errors, args.png, "validation errors per compensation method"))
        print(f"wrote {written[-1]}")
    write_command_report(args, written, default_folder(args) if args.json or not args.png else Path(args.png).parent)
    return 3 if len(untrusted) == len(runs) else 0          # as calibrate: 3 when no method's result is trusted


def _write_comparison(args, runs: list) -> list:
    """The Table 3 of this campaign as ``rodlab.comparison/1`` (to ``--json``, else in memory for the report)."""
    from ..report import FORMAT_COMPARISON, Source
    methods = {"nominal": runs[0][1].before.to_dict()}
    for name, run in runs:
        methods[name] = dict(run.after.to_dict(), fit_rms_um=run.result.rms_mm * 1e3, trusted=not run.result.warnings)
    data = {"format": FORMAT_COMPARISON, "robot": runs[0][1].robot.name, "campaign": str(args.campaign),
            "fixture": str(args.fixture), "validation": str(args.validate), "methods": methods}
    if not args.json:
        return [Source(FORMAT_COMPARISON, data)]
    path = atomic_write_json(args.json, json_safe(data))
    print(f"wrote {path}")
    return [path]
