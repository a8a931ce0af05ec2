"""``rodlab simulate-campaign``: a synthetic MultiCal campaign from a random truth robot (the project's test data)."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from rodlab.calibrate.device import ideal_device, misaligned_device, read_device, write_device
from rodlab.calibrate.effects import CAMPAIGN_EFFECTS, campaign_effect

from ...core.errors import RodlabError
from .argtypes import count, nonneg_float, seed
from .effectargs import effects_help, parse_effect_specs
from .robotargs import add_robot_options, robot_from_args
from .rodargs import compliance_arg

__all__ = ["register", "cmd_simulate_campaign"]


def register(sub) -> None:
    p = sub.add_parser("simulate-campaign", help="write a synthetic MultiCal campaign from a random truth robot",
                       formatter_class=argparse.RawDescriptionHelpFormatter,
                       description="The project's own test data: a truth robot (random kinematic errors, joint "
                                   "compliances), a fixture, a rod, noise; writes the contract's campaign, fixture, "
                                   "validation and compliance files and a truth.json. Effects the calibrator's "
                                   "model leaves out and their parameters (defaults: a typical magnitude):\n"
                                   + effects_help(CAMPAIGN_EFFECTS))
    add_robot_options(p)
    p.add_argument("--rod", required=True, help="the rod's compliance file (nominal), or a design (rod1 .. rod6, a "
                                                    "*.rod.toml) for its closed-form (calc) compliance")
    p.add_argument("--rod-true", default=None, help="the rod as it really is: a compliance file or a design (default: --rod)")
    p.add_argument("--positions", type=count, default=5, help="clamping positions (default 5, the paper's)")
    p.add_argument("--orientations", type=count, default=6, help="rod orientations per position (default 6)")
    p.add_argument("--noise-um", type=nonneg_float, default=3.0, help="device noise SD per reading [um] (default 3)")
    p.add_argument("--fixture-error", action="append", default=[], metavar="J:dx,dy,dz",
                   help="a wrong recorded pose: offset [mm] added to position J (the same as --effect "
                        "fixture_pose:position=J,offset_mm=dx;dy;dz)")
    p.add_argument("--effect", action="append", default=[], metavar="NAME[:key=value,...]",
                   help="add an effect (repeatable), e.g. periodic_joint_error:joint=4,amp_deg=0.006, "
                        "thermal_drift:growth_ppm_per_s=0.03, rod_deflection:k=1.5, outliers:count=3")
    p.add_argument("--raw", action="store_true",
                   help="write the device's three raw sensor readings (s1_mm, s2_mm, s3_mm; --noise-um per reading) "
                        "and its file multical.device.json (as built: sensors 2 and 3 off by --misalign-deg, springs "
                        "whose force follows each reading); nominal.device.json is the orthogonal design")
    p.add_argument("--misalign-deg", type=nonneg_float, default=None,
                   help="with --raw: how far sensors 2 and 3 are off orthogonal, each in a drawn direction [deg] "
                        "(default 1; with --device 0: the device as its file says)")
    p.add_argument("--device", default=None, metavar="DEV.device.json",
                   help="with --raw: your device's file (rodlab.device/1 or /2: its axes, zeros, ranges, springs, "
                        "reading signs, features) instead of the built-in orthogonal design; it is written as "
                        "nominal.device.json, and as multical.device.json turned by --misalign-deg")
    p.add_argument("--seed", type=seed, default=0, help="random seed of the truth robot, noise and effects (default 0)")
    p.add_argument("-o", "--output", required=True, help="output folder")
    p.set_defaults(func=cmd_simulate_campaign)


def cmd_simulate_campaign(args) -> int:
    from rodlab.calibrate.simulate import MAX_DEVICE_NOISE_MM, CampaignSpec, simulate_campaign
    robot = robot_from_args(args)
    rod = compliance_arg(args.rod)
    rod_true = compliance_arg(args.rod_true) if args.rod_true else None
    effects = []
    for it in args.fixture_error:
        j, _, v = it.partition(":")
        try:
            pos, off = int(j), [float(x) for x in v.split(",")]
        except ValueError:
            pos, off = 0, []
        if pos < 1 or len(off) != 3 or not all(map(math.isfinite, off)):
            raise RodlabError(f"--fixture-error {it!r}: expected J:dx,dy,dz (a position and three finite offsets "
                              f"[mm]), e.g. 2:0.05,0,-0.02")
        effects.append(("fixture_pose", {"position": pos, "offset_mm": off}))
    effects += parse_effect_specs(args.effect, campaign_effect)
    if args.noise_um * 1e-3 > MAX_DEVICE_NOISE_MM:
        raise RodlabError(f"--noise-um {args.noise_um:g}: at most {MAX_DEVICE_NOISE_MM * 1e3:g} um (a MultiCal device's "
                          "is 3 um)")
    spec = CampaignSpec(positions=args.positions, orientations=args.orientations, device_noise_mm=args.noise_um * 1e-3,
                        seed=args.seed)
    device = _simulated_device(args)
    truth = simulate_campaign(robot, rod, args.output, spec, rod_true=rod_true, effects=effects, device=device)
    print(f"wrote a {args.positions} x {args.orientations} campaign of {robot.name} with rod {rod.rod} to {args.output}")
    if device is not None:
        write_device(_base_device(args), Path(args.output) / "nominal.device.json")
        print(f"  raw sensor readings; device as built multical.device.json (sensor pairs off orthogonal by "
              f"{', '.join(f'{v:.2f}' for v in device.misalignment_deg())} deg), nominal.device.json the design"
              + (f" ({args.device})" if args.device else ""))
    for e in truth["effects"]:
        names = [p.name for p in campaign_effect(e["effect"]).params]
        print("  effect " + e["effect"] + ": " + ", ".join(f"{k}={e[k]}" for k in names if k in e))
    return 0


def _simulated_device(args):
    """``--raw``: the device as built, its misalignment drawn from a generator of its own (the campaign's other
    draws stay those of the same seed)."""
    if not args.raw:
        for given, what in ((args.misalign_deg is not None, "--misalign-deg tilts the simulated device's sensors"),
                            (args.device is not None, "--device gives the simulated device")):
            if given:                            # a device trial: --misalign-deg had been ignored without a word
                raise RodlabError(f"{what}, which only the raw readings show: give --raw with it (or leave it out)")
        return None
    misalign = (0.0 if args.device else 1.0) if args.misalign_deg is None else args.misalign_deg
    return misaligned_device(_base_device(args), misalign, np.random.default_rng([args.seed, 2]))


def _base_device(args):
    """The device as designed: the user's file (``--device``) or the built-in orthogonal one."""
    if args.device is None:
        return ideal_device()
    device = read_device(args.device)
    if not device.features_D_mm:
        raise RodlabError(f"{args.device}: the device file lists no features_D_mm, which the simulated probing of "
                          f"its clamping positions needs (multical.probe.csv); add the coordinates in {{D}} of the "
                          f"points an arm would probe (at least three, not on one line)")
    return device
