"""TCP targets for ``rodlab correct`` (``*.targets.csv``): one target per row, ``x_mm, y_mm, z_mm`` [mm] in the
calibration's measurement frame {W}, optionally ``q1..qn`` [deg], the program's configuration for that target
(the IK starts there); ``#`` lines are comments. And the commands file it writes."""
from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.fileio import atomic_write_text, read_text_checked

from .errors import CalibrationError

__all__ = ["Targets", "read_targets", "commands_csv"]


@dataclass(frozen=True)
class Targets:
    """targets_mm : shape=(M, 3) [mm] in {W}; q_seed_deg : shape=(M, n) [deg] or None; path : the file"""

    targets_mm: np.ndarray
    q_seed_deg: np.ndarray | None
    path: Path


def read_targets(path, n: int) -> Targets:
    """Read a targets file of an ``n``-joint robot; errors name the file, line and column."""
    p = Path(path)
    rows = [(k, r) for k, r in enumerate(csv.reader(io.StringIO(read_text_checked(p, CalibrationError))), start=1)
            if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise CalibrationError("no header: expected a line x_mm,y_mm,z_mm[,q1..qN]", path=p)
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
    want = ["x_mm", "y_mm", "z_mm"] + (qs if has_q else [])
    data = [[_number(r, cols.index(c), c, p, k) for c in want] for k, r in rows[1:]]
    if not data:
        raise CalibrationError("no targets below the header", path=p)
    a = np.array(data)
    return Targets(a[:, :3], a[:, 3:] if has_q else None, p)


def _number(row, idx: int, col: str, p: Path, line: int) -> float:
    try:
        v = float(row[idx])
    except (IndexError, ValueError):
        raise CalibrationError(f"expected a number, got {row[idx] if idx < len(row) else 'nothing'!r}", path=p,
                               line=line, key=col) from None
    if not math.isfinite(v):
        raise CalibrationError(f"expected a finite number, got {row[idx]!r}", path=p, line=line, key=col)
    return v


def commands_csv(path, targets: Targets, correction, predicted_mm: float | None, header: list[str]) -> Path:
    """Write the commands: per target the joint commands [deg], the corrected target for a nominal controller
    [mm], the IK residual [um], the uncorrected miss [mm], the calibration's predicted accuracy [mm], ok."""
    n = correction.q_rad.shape[1]
    lines = [f"# {h}" for h in header]
    lines.append(",".join(["target", "x_mm", "y_mm", "z_mm"] + [f"q{i + 1}" for i in range(n)]
                          + ["corrected_x_mm", "corrected_y_mm", "corrected_z_mm", "corrected_a_deg", "corrected_b_deg",
                             "corrected_c_deg", "residual_um", "uncorrected_mm",
                             "predicted_mm", "ok"]))
    pred = "" if predicted_mm is None else f"{predicted_mm:.4f}"
    q_deg = np.rad2deg(correction.q_rad)
    for k in range(len(targets.targets_mm)):
        cells = [str(k + 1)] + [f"{v:.6f}" for v in targets.targets_mm[k]] + [f"{v:.6f}" for v in q_deg[k]]
        cells += [f"{v:.6f}" for v in (*correction.corrected_mm[k], *correction.corrected_abc_deg[k])]
        cells += [f"{correction.residual_mm[k] * 1e3:.4f}", f"{correction.uncorrected_mm[k]:.4f}", pred,
                  str(int(correction.ok[k]))]
        lines.append(",".join(cells))
    return atomic_write_text(path, "\n".join(lines) + "\n")
