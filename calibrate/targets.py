"""TCP targets for ``rodlab correct`` (``*.targets.csv``): one target per row, ``x_mm, y_mm, z_mm`` [mm] in the
calibration's measurement frame {W}, optionally ``a_deg, b_deg, c_deg`` (all three: a pose target, the tool
frame's orientation in {W} in the contract's convention ``R = Rx(a) Ry(b) Rz(c)``) and ``q1..qn`` [deg], the
program's configuration for that target (the IK starts there); ``#`` lines are comments. And the commands file
it writes (docs/formats.md)."""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_text, read_text_checked

from .errors import CalibrationError

__all__ = ["Targets", "read_targets", "commands_csv"]


@dataclass(frozen=True)
class Targets:
    """targets_mm : shape=(M, 3) [mm] in {W}; q_seed_deg : shape=(M, n) [deg] or None; path : the file;
    abc_deg : shape=(M, 3) the tool frame's orientation in {W} (contract A, B, C [deg]) of pose targets, None for
    position targets; lines : shape=(M,) each target's line in the file (1-based), None when not read from one"""

    targets_mm: np.ndarray
    q_seed_deg: np.ndarray | None
    path: Path
    abc_deg: np.ndarray | None = None
    lines: np.ndarray | None = None

    @property
    def poses(self) -> bool:
        return self.abc_deg is not None


def read_targets(path, n: int) -> Targets:
    """Read a targets file of an ``n``-joint robot; errors name the file, line and column."""
    p = Path(path)
    rows = [(k, r) for k, r in enumerate(csv.reader(io.StringIO(read_text_checked(p, CalibrationError))), start=1)
            if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise CalibrationError("no header: expected a line x_mm,y_mm,z_mm[,a_deg,b_deg,c_deg][,q1..qN]", path=p)
    line0, header = rows[0]
    cols = [c.strip() for c in header]
    missing = [c for c in ("x_mm", "y_mm", "z_mm") if c not in cols]
    if missing:
        raise CalibrationError(f"missing column(s) {missing}; expected x_mm,y_mm,z_mm (and optionally q1..q{n} "
                               f"[deg], the program's configuration)", path=p, line=line0)
    qs = [f"q{i + 1}" for i in range(n)]
    has_q = any(c in cols for c in qs)
    if has_q and not all(c in cols for c in qs):
        raise CalibrationError(f"joint columns must be q1..q{n} (all of them, this is a {n}-joint robot), got "
                               f"{[c for c in cols if c.startswith('q')]}", path=p, line=line0)
    abc = _orientation_columns(cols, p, line0)
    want = ["x_mm", "y_mm", "z_mm"] + abc + (qs if has_q else [])
    data = [[_number(r, cols.index(c), c, p, k) for c in want] for k, r in rows[1:]]
    if not data:
        raise CalibrationError("no targets below the header", path=p)
    a = np.array(data)
    k = 3 + len(abc)
    return Targets(a[:, :3], a[:, k:] if has_q else None, p, a[:, 3:k] if abc else None,
                   np.array([line for line, _ in rows[1:]]))


ORIENTATION = ["a_deg", "b_deg", "c_deg"]


def _orientation_columns(cols: list, p: Path, line: int) -> list:
    """``a_deg, b_deg, c_deg`` if the header has them (a pose file), else none; a part of them, or another
    orientation convention, is refused with the fix."""
    have = [c for c in ORIENTATION if c in cols]
    foreign = [c for c in cols if c.lower() in ("qw", "qx", "qy", "qz", "roll", "pitch", "yaw", "rx", "ry", "rz",
                                               "roll_deg", "pitch_deg", "yaw_deg", "a", "b", "c")]
    if foreign:
        raise CalibrationError(f"orientation column(s) {foreign}: a pose target's orientation is given as a_deg, "
                               "b_deg, c_deg (the contract's A, B, C angles: R = Rx(a) Ry(b) Rz(c) [deg], the tool "
                               "frame in {W}); convert it to those three columns", path=p, line=line)
    if have and len(have) < 3:
        raise CalibrationError(f"a pose target needs all of a_deg, b_deg, c_deg; the header has only {have}: add the "
                               f"others (or remove them all for position targets)", path=p, line=line)
    return ORIENTATION if have else []


def _number(row, idx: int, col: str, p: Path, line: int) -> float:
    try:
        v = float(row[idx])
    except (IndexError, ValueError):
        raise CalibrationError(f"expected a number, got {row[idx] if idx < len(row) else 'nothing'!r}", path=p,
                               line=line, key=col) from None
    if not math.isfinite(v):
        raise CalibrationError(f"expected a finite number, got {row[idx]!r}", path=p, line=line, key=col)
    return v


def commands_csv(path, targets: Targets, correction, predicted_mm: float | None, header: list[str],
                 param_sd_mm: np.ndarray | None = None) -> Path:
    """Write the commands: per target the joint commands [deg], the corrected target for a nominal controller
    [mm], the IK residual [um], the uncorrected miss [mm], the calibration's predicted accuracy [mm] (its held-out
    mean), the TCP's 1-sigma uncertainty there from the identified parameters [mm] (empty without), ok."""
    n = correction.q_rad.shape[1]
    pose = targets.poses
    lines = [f"# {h}" for h in header]
    lines.append(",".join(["target", "x_mm", "y_mm", "z_mm"] + (ORIENTATION if pose else [])
                          + [f"q{i + 1}" for i in range(n)]
                          + ["corrected_x_mm", "corrected_y_mm", "corrected_z_mm", "corrected_a_deg", "corrected_b_deg",
                             "corrected_c_deg", "residual_um"] + (["residual_urad"] if pose else [])
                          + ["uncorrected_mm"] + (["uncorrected_mrad"] if pose else [])
                          + ["predicted_mm", "param_sd_mm", "ok"]))
    pred = "" if predicted_mm is None else f"{predicted_mm:.4f}"
    q_deg = np.rad2deg(correction.q_rad)
    for k in range(len(targets.targets_mm)):
        cells = [str(k + 1)] + [f"{v:.6f}" for v in targets.targets_mm[k]]
        cells += [f"{v:.9f}" for v in targets.abc_deg[k]] if pose else []
        cells += [f"{v:.9f}" for v in q_deg[k]]
        cells += [f"{v:.6f}" for v in correction.corrected_mm[k]] + [f"{v:.9f}" for v in correction.corrected_abc_deg[k]]
        cells += [f"{correction.residual_mm[k] * 1e3:.4f}"]
        cells += [f"{correction.residual_rad[k] * 1e6:.4f}"] if pose else []
        cells += [f"{correction.uncorrected_mm[k]:.4f}"]
        cells += [f"{correction.uncorrected_rad[k] * 1e3:.4f}"] if pose else []
        cells += [pred, "" if param_sd_mm is None else f"{param_sd_mm[k]:.4f}", str(int(correction.ok[k]))]
        lines.append(",".join(cells))
    return atomic_write_text(path, "\n".join(lines) + "\n")
