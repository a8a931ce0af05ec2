"""``rodlab report``: one self-contained HTML page of any rodlab output folder."""
from __future__ import annotations

import argparse

__all__ = ["register"]


def register(sub) -> None:
    p = sub.add_parser("report", help="one self-contained HTML page of any rodlab output folder",
                       description="A demo folder gives the demo's page (design, CAD, FEA, rig fit, diagnosis, "
                                   "calibration, sweep, study). Any other folder: every rodlab result found in it "
                                   "and two levels below (compliance, joints, sweep, study, calibration, comparison, "
                                   "diagnosis, CAD mass files, recognised by their format key) with its figures; "
                                   "figures embedded, no links out.")
    p.add_argument("run_dir", metavar="DIR", help="a folder rodlab wrote into")
    p.add_argument("-o", "--output", default=None, help="default DIR/report.html")
    p.set_defaults(func=cmd_report)


def cmd_report(args: argparse.Namespace) -> int:
    from ..report import write_folder_report
    print(f"wrote {write_folder_report(args.run_dir, args.output)}")
    return 0
