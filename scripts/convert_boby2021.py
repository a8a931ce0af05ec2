"""Convert the public laser-tracker data set of Boby & Klimchik to rodlab's instrument-point files.

Source: github.com/RABKKK/LaserTrackerPoseData4KinIdent, file ``N1N2N3Jval.csv`` (data of R. A. Boby,
A. Klimchik, "Combination of geometric and parametric approaches for kinematic identification of an
industrial robot", Robotics and Computer-Integrated Manufacturing, 2021). One row per robot pose: the
positions [mm] of three reflectors (SMR N1, N2, N3) on the end-effector, measured by a laser tracker, then
joint values [deg] from the controller (in the stored copy: six zero columns, then J1..J6).

The robot is a FANUC R-2000iC/165F (see ``calibrate/robots/r2000ic165f.urdf`` and docs/calibrate.md for
how this was established from the data). The controller's joints become the URDF's joints (the
ROS-Industrial layout; FANUC reports J3 relative to the horizontal): ``q = (J1, J2, J2 + J3, J4, J5, J6)``.
Each reflector becomes one ``*.validation.csv`` (the
contract's instrument-point format) with a rough tool guess; ``rodlab calibrate --points`` finds the real
tool and base.

    python scripts/convert_boby2021.py N1N2N3Jval.csv -o benchmarks/data/boby2021
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_text

HEADER = """# Laser-tracker points of a FANUC R-2000iC/165F, reflector {name} (public data of R. A. Boby and
# A. Klimchik, github.com/RABKKK/LaserTrackerPoseData4KinIdent, N1N2N3Jval.csv; converted by
# scripts/convert_boby2021.py). q = (J1, J2, J2+J3, J4, J5, J6) [deg] (ROS-I); x, y, z in the tracker frame.
# The tool below is a rough guess (reflector ~200 mm in front of the flange); calibration finds it.
# tool_mm: 0, 0, 200
# rod_mass_kg: 0
# rod_com_T_mm: 0, 0, 0
"""


def controller_to_model(J_deg: np.ndarray) -> np.ndarray:
    """FANUC controller joints (J3 relative to the horizontal) to the URDF's q, shape=(N, 6) [deg]."""
    q = np.array(J_deg, float)
    q[:, 2] += q[:, 1]
    return q


def convert(src: Path, out: Path) -> list[Path]:
    data = np.loadtxt(src, ndmin=2)
    if data.shape[1] not in (15, 21):
        raise SystemExit(f"{src}: expected 21 columns (9 reflector coordinates, 6 zeros, J1..J6) or 15, "
                         f"got {data.shape[1]}")
    q = controller_to_model(data[:, -6:])
    keep = np.ones(len(data), bool)
    keep[1:] = np.any(np.abs(np.diff(data, axis=0)) > 0, axis=1)     # the source repeats one pose verbatim
    written = []
    for k, name in enumerate(("N1", "N2", "N3")):
        x = data[:, 3 * k:3 * k + 3]
        rows = [",".join(f"{v:.3f}" for v in (*qq, *xx)) for qq, xx, ok in zip(q, x, keep) if ok]
        text = HEADER.format(name=name) + "q1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm\n" + "\n".join(rows) + "\n"
        written.append(atomic_write_text(out / f"r2000ic_{name}.validation.csv", text))
    return written


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("source", type=Path, help="N1N2N3Jval.csv from the source repository")
    ap.add_argument("-o", "--out", type=Path, default=Path("benchmarks/data/boby2021"))
    a = ap.parse_args(argv)
    for p in convert(a.source, a.out):
        print(f"wrote {p}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
