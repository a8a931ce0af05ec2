"""``--columns-checked``: go on with joint readings the mix-up screen refuses (instrument points, socket readings)."""
from __future__ import annotations

import sys

from rodlab.calibrate.mixups import refuse_mixed_up_joints

__all__ = ["COLUMNS_CHECKED_HELP", "add_columns_checked", "screen_joint_columns"]

COLUMNS_CHECKED_HELP = ("the joint columns of the points, socket readings or campaign are right as they are (each "
                        "joint's sign, order and zero as the robot file's; a campaign's positions and fixture as "
                        "given): warn of a mix-up the screen finds instead of refusing the files")

#: appended to a refusal: how to go on regardless
_HINT = " (if the file's joint columns are right as they are, give --columns-checked)"


def add_columns_checked(p) -> None:
    """Register ``--columns-checked`` on the sub-command parser ``p``."""
    p.add_argument("--columns-checked", action="store_true", help=COLUMNS_CHECKED_HELP)


def screen_joint_columns(args, robot, readings, path, noise_mm: float | None = None, done: str = "calibrated") -> None:
    """Refuse ``readings`` (from ``path``) whose joint columns are mixed up against ``robot``
    (:func:`~rodlab.calibrate.mixups.refuse_mixed_up_joints`), or with ``--columns-checked`` warn of it."""
    mixup = refuse_mixed_up_joints(robot, readings, path, noise_mm, done, checked=args.columns_checked, hint=_HINT)
    if mixup is not None:
        print(f"warning: {path}: {mixup.reason()} (--columns-checked: {done} as they are)", file=sys.stderr)
