"""``--device DEV.device.json``: read a campaign of raw sensor readings (``s1_mm, s2_mm, s3_mm``) through its
device file, and warn where the ball sat farther from the datum than the paper's alignment."""
from __future__ import annotations

import sys

from rodlab.calibrate import read_campaign, read_points
from rodlab.calibrate.device import read_device
from rodlab.calibrate.readings import (ALIGNMENT_LIMIT_MM, common_offset, far_points, limit_breaches,
                                      point_unit_slips, unit_slips)

from ...core.errors import RodlabError

__all__ = ["DEVICE_HELP", "add_device_option", "campaign_from_args", "points_from_args", "warn_flagged_fixture",
           "refuse_rod_slips", "flagged_fixture_reasons"]

DEVICE_HELP = ("the 3-D device's file (*.device.json) for a campaign of raw sensor readings (s1_mm, s2_mm, s3_mm): "
               "each point is solved from its readings, the sensors' noise (--noise-um, per reading) is propagated "
               "through the axes, the springs' force at each reading is the contact force, and a reading outside "
               "its sensor's range is refused")


UNITS_CHECKED_HELP = ("the campaign's units are right although its numbers look like radians or um (a campaign that "
                      "turns every joint by less than 6.3 deg, or points measured far from the datum), and the rod's "
                      "compliance file's although it looks like um/N, grams or metres: warn instead of refusing")


def add_device_option(p, prefix: str = "", units_also: str = "") -> None:
    """``--device`` and ``--units-checked``, the options of a campaign read by :func:`campaign_from_args`;
    ``units_also``: what else the command's ``--units-checked`` lets through."""
    p.add_argument("--device", default=None, metavar="DEV.device.json", help=prefix + DEVICE_HELP)
    p.add_argument("--units-checked", action="store_true", help=prefix + UNITS_CHECKED_HELP + units_also)


def campaign_from_args(args, robot, warn: bool = True):
    """``args.campaign`` read for ``robot`` (with ``args.device`` when given); with ``warn`` the points far from the
    datum and the rows beyond the robot's joint limits are named on stderr."""
    device = read_device(args.device) if getattr(args, "device", None) else None
    camp = read_campaign(args.campaign, robot.n, device)
    _refuse_slips(unit_slips(camp, args.campaign), args)
    if warn:
        _warn_limits(camp.q_deg, camp.lines, robot, args.campaign)
    if warn and camp.x_D_mm is not None:
        far = far_points(camp)
        if far:
            shown = "; ".join(str(f) for f in far[:5]) + (f"; and {len(far) - 5} more" if len(far) > 5 else "")
            print(f"warning: {args.campaign}: {len(far)} point(s) farther than {ALIGNMENT_LIMIT_MM:g} mm from the "
                  f"datum point (the alignment the paper assumes; the springs' force and the rod's deflection "
                  f"differ there): {shown}{_common_offset(camp.x_D_mm, args)}", file=sys.stderr)
    return camp


def _common_offset(x_D_mm, args) -> str:
    """Where most points are far from the datum by one offset (:func:`~calibrate.readings.common_offset`): what
    that says (a device file with another zero, or readings zeroed elsewhere); else ""."""
    mean = common_offset(x_D_mm)
    if mean is None:
        return ""
    offset = ", ".join(f"{v:+.2f}" for v in mean)
    zero = (f"the device file {args.device} has another zero (zero_mm) or datum than the device that recorded "
            "them, or two of its sensors' columns are exchanged (a refusal below names that)"
            if getattr(args, "device", None) else "the sensors were zeroed elsewhere than at the datum point")
    return f"; they share one offset ({offset}) mm in {{D}}: {zero}"



def points_from_args(args, path, robot):
    """Instrument points (``*.validation.csv``) read from ``path`` for ``robot``, refused where their numbers look
    like radians or metres (unless ``--units-checked``; their sigma columns not judged where ``--noise-um`` replaces
    them); rows beyond the robot's joint limits named on stderr."""
    points = read_points(path, robot.n)
    _refuse_slips(point_unit_slips(points, path, sigmas=not getattr(args, "noise_um", None)), args)
    _warn_limits(points.q_deg, None, robot, path)
    return points


def _warn_limits(q_deg, lines, robot, path) -> None:
    for breach in limit_breaches(q_deg, lines, robot, path):
        print(f"warning: {breach}", file=sys.stderr)


def refuse_rod_slips(rod, spec: str, args, option: str = "--rod") -> None:
    """A compliance file whose numbers no measuring rod has (C_F in um/N, a mass in grams, a tool in metres:
    :meth:`~rodlab.core.compliance.RodCompliance.unit_slips`) is refused before a calibration uses it, or with
    ``--units-checked`` warned of (a paper trial: C_F in um/N had been warned of and then compensated, 77 mm of
    residuals blamed on the fixture)."""
    _refuse_slips([f"{option} {spec}: {slip}" for slip in rod.unit_slips()], args)


def _refuse_slips(slips: list, args) -> None:
    """Refuse what :func:`unit_slips` found, or with ``--units-checked`` warn of it."""
    if slips and not getattr(args, "units_checked", False):
        raise RodlabError("; ".join(slips) + "; if the units are right, give --units-checked")
    for slip in slips:
        print(f"warning: {slip} (--units-checked: used as they are)", file=sys.stderr)


def warn_flagged_fixture(fix, path) -> None:
    """A fixture file whose probing flagged positions (``rodlab fixture`` exit 3) is named on stderr."""
    where = _flagged_where(fix)
    if where:
        print(f"warning: {path}: its probing flagged {where} (residuals above the instrument's accuracy); those "
              f"poses may be wrong: probe again", file=sys.stderr)


def flagged_fixture_reasons(fix, path) -> list[str]:
    """A reason not to trust a calibration that names the fixture file's flagged probing (empty when none): with
    residuals that are not noise, a pose the probing already doubted is the likeliest cause."""
    where = _flagged_where(fix)
    if not where:
        return []
    return [f"the fixture file {path} was written with its probing flagged ({where}): those clamping poses are the "
            "first suspects; probe them again (`rodlab fixture`) and calibrate with the new fixture file"]


def _flagged_where(fix) -> str:
    """The fixture file's flagged probing, ``position j: what; ...`` ("" when none)."""
    flagged = (fix.probing or {}).get("flagged") or {}
    return "; ".join(f"position {j}: {what}" for j, what in flagged.items())
