"""argparse value types that refuse what no command can use (negative counts and seeds, NaN, inf), so the
error names the option (``argument --seed: expected an integer >= 0, got '-1'``) before any work starts."""
from __future__ import annotations

import argparse
import math

import numpy as np

__all__ = ["seed", "count", "nonneg_float", "pos_float", "joint_list", "base_pose"]


def _int(text: str, low: int, what: str) -> int:
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if v < low or v > 2**32 - 1:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


def _float(text: str, positive: bool) -> float:
    what = "a finite number > 0" if positive else "a finite number >= 0"
    try:
        v = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if not math.isfinite(v) or v < 0 or (positive and v == 0):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return v


def seed(text: str) -> int:
    """A random seed: an integer 0 .. 2^32 - 1."""
    return _int(text, 0, "an integer seed from 0 to 4294967295")


def count(text: str) -> int:
    """A number of things: an integer >= 1."""
    return _int(text, 1, "a whole number >= 1")


def nonneg_float(text: str) -> float:
    return _float(text, False)


def pos_float(text: str) -> float:
    return _float(text, True)


seed.__name__ = "seed"
count.__name__ = "count"
nonneg_float.__name__ = "number >= 0"
pos_float.__name__ = "number > 0"


def joint_list(text: str) -> tuple:
    """``"1,4"`` -> (1, 4): joint numbers (1-based; the robot's own check names joints it does not have)."""
    try:
        joints = tuple(sorted({int(t) for t in text.split(",") if t.strip()}))
    except ValueError:
        joints = ()
    if not joints or min(joints) < 1:
        raise argparse.ArgumentTypeError(f"expected joint numbers separated by commas, e.g. 1,4; got {text!r}")
    return joints


def base_pose(text: str):
    """``--base X,Y,Z,A,B,C``: six finite numbers [mm, deg] (the robot base {0} in {W}), as a numpy array."""
    try:
        v = np.array([float(t) for t in text.split(",")])
    except ValueError:
        v = np.array([])
    if v.shape != (6,) or not np.all(np.isfinite(v)):
        raise argparse.ArgumentTypeError(f"expected six numbers X,Y,Z,A,B,C (the base pose in {{W}}, mm and deg), "
                                         f"got {text!r}")
    return v
