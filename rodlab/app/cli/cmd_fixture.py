"""``rodlab fixture``: the fixture file's clamping poses, with their uncertainty, from probed device features."""
from __future__ import annotations

import math
import sys
from pathlib import Path

from rodlab.calibrate import write_fixture
from rodlab.calibrate.device import read_device
from rodlab.calibrate.probe import fit_fixture, read_probe

from ...core.errors import RodlabError
from .argtypes import count

__all__ = ["register", "cmd_fixture"]


def register(sub) -> None:
    p = sub.add_parser("fixture", help="fit the fixture's clamping poses from probed device features",
                       description="Fits the device frame {D_j} of every probed clamping position to its reference "
                                   "features (features_D_mm of the device file) measured by a measuring arm or laser "
                                   "tracker (PROBE.csv: position,feature,x_mm,y_mm,z_mm in its own frame, "
                                   "'# accuracy_mm:' its accuracy): least squares, each pose's covariance from the "
                                   "accuracy. Writes the poses in {W} = {D_world} with their covariance "
                                   "(rodlab.fixture/2; the calibration's noise model uses it) and flags a position "
                                   "whose residuals exceed the accuracy (exit 3).")
    p.add_argument("probe", help="*.probe.csv")
    p.add_argument("--device", required=True, help="the device's *.device.json (its features_D_mm)")
    p.add_argument("--world-position", type=count, required=True,
                   help="the clamping position whose device frame is the world frame {W}")
    p.add_argument("--contact-force", default=None, metavar="FX,FY,FZ",
                   help="contact force on the ball in {D} [N] for the file (default: the device's springs at the "
                        "datum, else 1.10,1.25,1.05)")
    p.add_argument("-o", "--output", required=True, help="the *.fixture.json to write")
    p.set_defaults(func=cmd_fixture)


def _force(text):
    if text is None:
        return None
    try:
        v = [float(x) for x in text.split(",")]
    except ValueError:
        v = []
    if len(v) != 3 or not all(map(math.isfinite, v)):
        raise RodlabError(f"--contact-force {text!r}: expected three finite numbers FX,FY,FZ [N], e.g. 1.10,1.25,1.05")
    return v


def _all_flagged(fit, device) -> str:
    """What every position flagged says: one suspect feature at each, the device file (another device's
    features, swapped names, or that feature moved); different ones, first the stated accuracy (a repeatability
    given as the 1-sigma accuracy), then the device file."""
    suspects = sorted({f.suspect[0] for f in fit.flagged})
    n = len(fit.flagged)
    swaps = {tuple(sorted(f.swapped)) if f.swapped is not None else None for f in fit.flagged}
    if len(swaps) == 1 and None not in swaps:
        a, b = swaps.pop()
        return (f"FLAGGED all {n} positions, each fitting with {a!r} and {b!r} exchanged: the same two labels swap "
                f"everywhere, so the device file {device} most likely has their coordinates exchanged (or the probing "
                f"routine names them so); exchange {a!r} and {b!r} in its features_D_mm (or in the routine) and run "
                f"`rodlab fixture` again")
    if len(suspects) == 1:
        return (f"FLAGGED all {n} positions with the same suspect feature {suspects[0]!r}: the device file {device} "
                f"does not describe the device that was probed (its features_D_mm are another device's, the probe "
                f"file's feature names are swapped, or {suspects[0]!r} moved on the device: a loose seat); give this "
                f"device's file (rodlab.device/1 or /2) or re-measure the feature, then run `rodlab fixture` again")
    return (f"FLAGGED all {n} positions, with different suspect features: the probe file's accuracy_mm "
            f"({fit.accuracy_mm:g} mm) may be the instrument's repeatability rather than its 1-sigma accuracy (state "
            f"the accuracy), or the device file {device} is another device's")


def cmd_fixture(args) -> int:
    force = _force(args.contact_force)
    fit = fit_fixture(read_probe(args.probe), read_device(args.device), args.world_position, force)
    print(f"fixture from {args.probe}: {len(fit.fits)} positions, world position {args.world_position}, instrument "
          f"accuracy {fit.accuracy_mm * 1e3:g} um")
    print("  position  features  rms resid um   sigma x,y,z um        sigma a,b,c mdeg")
    for j, f in sorted(fit.fits.items()):
        s = fit.sigmas(j)
        mark = "  FLAGGED" if f.flagged else ""
        print(f"  {j:>8}  {len(f.features):>8}  {f.rms_mm * 1e3:12.1f}   {s[0] * 1e3:5.1f} {s[1] * 1e3:5.1f} "
              f"{s[2] * 1e3:5.1f}   {s[3] * 1e3:6.1f} {s[4] * 1e3:6.1f} {s[5] * 1e3:6.1f}{mark}")
    if any(f.swapped is not None for f in fit.flagged):    # poses fitted on exchanged labels are wrong by cm
        stale = (f"; the {args.output} already there is an earlier run's, not this probing's: do not calibrate with "
                 f"it" if Path(args.output).exists() else "")
        print(f"not written: {args.output} (positions with exchanged labels, below){stale}", file=sys.stderr)
    else:
        print(f"wrote {write_fixture(fit.fixture, args.output)}")
    if len(fit.flagged) >= 2 and len(fit.flagged) == len(fit.fits):
        print(_all_flagged(fit, args.device), file=sys.stderr)
    for f in fit.flagged:
        name, d = f.suspect
        head = (f"FLAGGED position {f.position}: residuals exceed the instrument's accuracy (chi-square {f.chi2:.1f} "
                f"over {f.dof} degrees of freedom, p = {f.p:.1e}); ")
        if f.swapped is not None:
            a, b = f.swapped
            print(head + f"features {a!r} and {b!r} are swapped: with their labels exchanged the position fits within "
                  f"the accuracy. Exchange them in {args.probe} at position {f.position} and run `rodlab fixture` "
                  "again", file=sys.stderr)
            continue
        print(head + f"suspect feature {name!r}, {d * 1e3:.0f} um off the fit of the others. "
              f"Probe it again or check the device's seat before calibrating", file=sys.stderr)
    return 3 if fit.flagged else 0
