"""Convert the public laser-tracker data set of P. Jacobi (UR5) to rodlab's instrument-point files.

Source: github.com/pauljac7700/serial_robots_datasets (MIT licence; P. Jacobi, "A Hybrid Error Compensation
Method for Enhancing the Pose Accuracy of Serial Industrial Robots", Master's thesis, Tsinghua University,
2025). A Universal Robots UR5 carries a 1.5" SMR whose position a GTS3800 laser tracker measures
(15 um + 6 um/m); the tracker's frame was registered to the robot's base before the data were taken:

  UR5/3D_UR5_uncalibrated_grid_cleaned.csv     1000 poses on a grid over the workspace (calibration set)
  UR5/3D_UR5_uncalibrated_random_cleaned.csv   20 random poses (the source's test set)

Columns used: ``joint_1`` .. ``joint_6`` [deg], the commanded joints, which are the URDF's joints
(calibrate/robots/ur5.urdf); ``x_t, y_t, z_t`` [mm], the target: the nominal forward kinematics of those
joints with the source's tool-centre frame (UR's DH with a tool of about (0, 0.07, 31.0) mm reproduces them to
0.007 mm rms, 0.04 mm at most), in UR's ``base`` frame (ur_description's ``base``, turned 180 deg about z from
``base_link``: a calibration reads base_c near -180 deg); ``x_dif, y_dif, z_dif`` [mm], "the difference between
the target and the actual position". The measured position written is target + difference: for every value
of both files that sum is a number with six decimals, as the tracker's readings were recorded, and target
minus difference is not (9 of 3,060): the difference was computed as measured minus target. The script
checks this and warns if a file breaks it. The SMR and its nest (some 0.2 kg) are not in the source, so the
payload is 0. The Barrett WAM files of the source (a cable-driven arm, 2 mm repeatability, no URDF in
rodlab) are not converted. The tool guess is the source's tool-centre frame, 30 mm along the flange's z.

    python scripts/convert_jacobi2025.py SRC_DIR -o benchmarks/data/jacobi2025

SRC_DIR is a checkout of the source repository (or a folder holding the two CSV files).
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from source_tables import column, convert_main, warn_if_changed

SETS = {"grid": "3D_UR5_uncalibrated_grid_cleaned.csv", "random": "3D_UR5_uncalibrated_random_cleaned.csv"}
#: sha256 of the source files this script was written for (git commit 759068d of the source repository)
SHA256 = {"grid": "3de63c38b4338a1fb23437a9c6ecb7e0441a9e132fc055544619b8c580f767c0",
          "random": "3cd7a4aae072f9757ce9bd156e7470cc8caa89d8af9164c07390953ae808095a"}
JOINTS = [f"joint_{i}" for i in range(1, 7)]
HEADER = """# Laser-tracker points of a Universal Robots UR5, {name}: public data of P. Jacobi,
# github.com/pauljac7700/serial_robots_datasets (MIT; {source}), converted by
# scripts/convert_jacobi2025.py.
# q [deg] are the URDF's joints (calibrate/robots/ur5.urdf); x, y, z [mm] the SMR position measured by a
# GTS3800 laser tracker, in UR's base frame as the source registered it (target + difference).
# The tool below is the source's nominal tool-centre frame; calibration finds the real one.
# tool_mm: 0, 0, 30
# rod_mass_kg: 0
# rod_com_T_mm: 0, 0, 0
"""


def convert_set(path: Path, name: str) -> str:
    """The rodlab points file (text) of one source file."""
    return points_text(path, SHA256[name], JOINTS, HEADER.format(name=f"{name} poses", source=path.name), 4)


def points_text(path: Path, sha256: str, joints: list, head: str, digits: int) -> str:
    """A rodlab points file (text) from one of the source's files: its ``joints`` columns [deg] and the measured
    position target + difference [mm] (checked to be six-decimal readings), written with ``digits`` decimals under
    the comment block ``head``."""
    warn_if_changed(path, sha256)
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    q = np.column_stack([column(rows, j, path) for j in joints])
    target = np.column_stack([column(rows, f"{c}_t", path) for c in "xyz"])
    diff = np.column_stack([column(rows, f"{c}_dif", path) for c in "xyz"])
    x = target + diff
    off_grid = int(np.sum(np.abs(x * 1e6 - np.round(x * 1e6)) > 1e-3))
    if off_grid:
        print(f"warning: {path}: {off_grid} of {x.size} values of target + difference are not six-decimal readings; "
              f"check the sign of the difference columns", file=sys.stderr)
    lines = [",".join([f"{v:.6f}" for v in qq] + [f"{v:.{digits}f}" for v in xx]) for qq, xx in zip(q, x)]
    names = ",".join(f"q{i}" for i in range(1, len(joints) + 1))
    return head + names + ",x_mm,y_mm,z_mm\n" + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    return convert_main(argv, __doc__, "benchmarks/data/jacobi2025", SETS, "github.com/pauljac7700/serial_robots_datasets",
                        convert_set, lambda key: f"ur5_{key}.validation.csv")


if __name__ == "__main__":
    sys.exit(main())
