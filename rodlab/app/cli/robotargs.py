"""The robot options every command that models a robot shares: ``--robot``, ``--base-link``, ``--tip-link``."""
from __future__ import annotations

from rodlab.calibrate import resolve_robot
from rodlab.calibrate.robot_formats import robot_formats_help

__all__ = ["add_robot_options", "robot_from_args", "robot_help"]


def robot_help() -> str:
    """``--robot``'s help: the built-in robots and the robot file formats, from the registry
    (:data:`rodlab.calibrate.robot_formats.ROBOT_READERS`)."""
    return robot_formats_help()


def add_robot_options(p, default: str | None = "tx90", help: str | None = None) -> None:
    p.add_argument("--robot", default=default, help=robot_help() if help is None else help)
    p.add_argument("--base-link", default=None, metavar="LINK",
                   help="URDF robots: the chain's first link (default: the root link, e.g. base_link)")
    p.add_argument("--tip-link", default=None, metavar="LINK",
                   help="URDF robots: the chain's last link (default: tool0, else the deepest leaf)")


def robot_from_args(args):
    """The robot the options name (a URDF's chain between --base-link and --tip-link)."""
    return resolve_robot(args.robot, getattr(args, "base_link", None), getattr(args, "tip_link", None))
