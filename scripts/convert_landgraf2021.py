"""Convert the public laser-tracker data set of Landgraf et al. (UR10) to rodlab's instrument-point files.

Source: github.com/christianlandgraf/ipa-robot-accuracy (MIT licence; C. Landgraf, K. Ernst, G. Schleth,
M. Fabritius, M. F. Huber, "A Hybrid Neural Network Approach for Increasing the Absolute Accuracy of
Industrial Robots", IEEE CASE 2021). A Universal Robots UR10 (CB3) carries a Leica T-Mac whose pose a laser
tracker measures; each series is one measurement campaign with its own tracker placement:

  Series_B/measurements_joint_configurations.csv   1495 poses from a joint-space plan
  Series_C/measurements_random_poses.csv           2773 random poses
  Series_D/measurements_iso_cubes.csv              632 poses on ISO 9283 test cubes (a later campaign)

Columns used: the six joint values [rad] (``shoulder_pan_joint`` .. ``wrist_3_joint``, the URDF's joints,
as the UR controller reports them), the T-Mac position in the tracker frame ``measurement_x/y/z`` [mm] and
its standard deviation over the tracker's averaging ``measurement_std_x/y/z`` [mm] (written as the optional
per-point uncertainty columns), ``measurement_temperature`` [degC] (its mean goes to ``# temp_C``). The
source uses ``;`` separators and decimal commas. The tool guess is the T-Mac's nominal offset from the flange
(109 mm along z, the series' ``Trafo_TM_F_init.txt``); calibration finds the real one. The T-Mac's mass is not
stated in the source, so ``rod_mass_kg`` is 0 (no payload torque).

    python scripts/convert_landgraf2021.py SRC_DIR -o benchmarks/data/landgraf2021

SRC_DIR is a checkout of the source repository (or a folder holding the three CSV files).
"""
from __future__ import annotations

import csv
import sys
from pathlib import Path

import numpy as np

from source_tables import column, convert_main, warn_if_changed

SERIES = {"B": "measurements_joint_configurations.csv", "C": "measurements_random_poses.csv",
          "D": "measurements_iso_cubes.csv"}
#: sha256 of the source files this script was written for (git commit 507fba6 of the source repository)
SHA256 = {"B": "12b69a4e6ff7be68e67d3f70245a3ab7bb6ec3a2c63bc5eae002b15a1f863d7e",
          "C": "904a1d195e558315bd21469abb02bfcc000dd1296c0cd68eb86c62e95f7ba160",
          "D": "a49dfd2182e662e65c217b00015433f5048ebad0f04c46c33c97a5c4a5643332"}
JOINTS = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint", "wrist_2_joint",
          "wrist_3_joint"]
HEADER = """# Laser-tracker points of a Universal Robots UR10 (CB3), series {series} ({name}): public data of
# C. Landgraf et al., github.com/christianlandgraf/ipa-robot-accuracy (MIT), converted by
# scripts/convert_landgraf2021.py. q [deg] are the URDF's joints (calibrate/robots/ur10.urdf); x, y, z [mm]
# the T-Mac position in the tracker frame; sigma_* [mm] the tracker's standard deviation of each point.
# The tool below is the T-Mac's nominal offset; calibration finds the real one.
# tool_mm: 0, 0, 109
# rod_mass_kg: 0
# rod_com_T_mm: 0, 0, 0
# temp_C: {temp:.2f}
"""


def convert_series(path: Path, series: str) -> str:
    """The rodlab points file (text) of one source series."""
    warn_if_changed(path, SHA256[series])
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.DictReader(f, delimiter=";"))
    q = np.rad2deg(np.column_stack([column(rows, j, path, decimal_comma=True) for j in JOINTS]))
    x = np.column_stack([column(rows, f"measurement_{c}", path, decimal_comma=True) for c in "xyz"])
    s = np.column_stack([column(rows, f"measurement_std_{c}", path, decimal_comma=True) for c in "xyz"])
    s = np.maximum(s, 1e-4)                 # a few rows state 0: the tracker's resolution instead
    temp = float(np.mean(column(rows, "measurement_temperature", path, decimal_comma=True)))
    lines = [",".join([f"{v:.5f}" for v in qq] + [f"{v:.4f}" for v in xx] + [f"{v:.4f}" for v in ss])
             for qq, xx, ss in zip(q, x, s)]
    head = HEADER.format(series=series, name=path.name, temp=temp)
    cols = "q1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm,sigma_x_mm,sigma_y_mm,sigma_z_mm\n"
    return head + cols + "\n".join(lines) + "\n"


def main(argv=None) -> int:
    return convert_main(argv, __doc__, "benchmarks/data/landgraf2021", SERIES, "github.com/christianlandgraf/ipa-robot-accuracy",
                        convert_series, lambda key: f"ur10_{key}.validation.csv")


if __name__ == "__main__":
    sys.exit(main())
