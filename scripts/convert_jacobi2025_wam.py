"""Convert the Barrett WAM laser-tracker data of P. Jacobi to rodlab's instrument-point files.

Source: github.com/pauljac7700/serial_robots_datasets (MIT licence; P. Jacobi, "A Hybrid Error Compensation
Method for Enhancing the Pose Accuracy of Serial Industrial Robots", Master's thesis, Tsinghua University,
2025), the same repository and tracker (GTS3800, 1.5" SMR, 15 um + 6 um/m) as the UR5 files
(scripts/convert_jacobi2025.py). A Barrett WAM is a 7-joint cable-driven arm (repeatability 2 mm):

  WAM/3D_WAM_uncalibrated_grid_cleaned.csv     216 poses on a grid (calibration set)
  WAM/3D_WAM_uncalibrated_random_cleaned.csv   20 random poses (the source's test set)

Columns used: ``joint_1`` .. ``joint_7`` [deg]; ``x_t, y_t, z_t`` [mm], the target (Barrett's standard DH,
benchmarks/data/jacobi2025/wam7.toml, with a tool 44 mm along the flange's z reproduces them to 0.3 um: a
real-data trial); ``x_dif, y_dif, z_dif`` [mm]. The measured position is target + difference (six-decimal
readings, as for the UR5; checked). The payload is not in the source: 0.

    python scripts/convert_jacobi2025_wam.py SRC_DIR -o benchmarks/data/jacobi2025
"""
from __future__ import annotations

import sys
from pathlib import Path

from convert_jacobi2025 import points_text
from source_tables import convert_main

SETS = {"grid": "3D_WAM_uncalibrated_grid_cleaned.csv", "random": "3D_WAM_uncalibrated_random_cleaned.csv"}
#: sha256 of the source files this script was written for (git commit 759068d of the source repository)
SHA256 = {"grid": "f013c0ce152cffb5f529e747681457d359a9869c46fdbb4f4e1eefb8234835ad",
          "random": "b9b6f5ee9f4e9fce0ed8a70d458b08b6af7f473afe98bb92ac2ff379d398e5e2"}
JOINTS = [f"joint_{i}" for i in range(1, 8)]
HEADER = """# Laser-tracker points of a Barrett WAM (7 joints, cable-driven), {name}: public data of P. Jacobi,
# github.com/pauljac7700/serial_robots_datasets (MIT; {source}), converted by
# scripts/convert_jacobi2025_wam.py.
# q [deg] are the joints of benchmarks/data/jacobi2025/wam7.toml (Barrett's standard DH); x, y, z [mm] the SMR
# position measured by a GTS3800 laser tracker in the frame the source registered (target + difference).
# The tool below reproduces the source's targets; calibration finds the real one.
# tool_mm: 0, 0, 44
# rod_mass_kg: 0
# rod_com_T_mm: 0, 0, 0
"""


def convert_set(path: Path, name: str) -> str:
    """The rodlab points file (text) of one source file (as the UR5's: :func:`convert_jacobi2025.points_text`)."""
    return points_text(path, SHA256[name], JOINTS, HEADER.format(name=f"{name} poses", source=path.name), 6)


def main(argv=None) -> int:
    return convert_main(argv, __doc__, "benchmarks/data/jacobi2025", SETS, "github.com/pauljac7700/serial_robots_datasets",
                        convert_set, lambda key: f"wam_{key}.validation.csv")


if __name__ == "__main__":
    sys.exit(main())
