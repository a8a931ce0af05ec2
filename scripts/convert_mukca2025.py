"""Convert the public ball-in-socket data of MUKCa (Franzese et al.) to rodlab's socket files.

Source: github.com/platonics-delft/kinematics_calibration (MIT licence; G. Franzese, M. Spahn, M. Ramirez,
"MUKCa: Accurate and Affordable Cobot Calibration Without External Measurement Devices", 2025). A 3D-printed
artefact with two sockets 50 mm apart (the source's ``offset_distance``) is placed at several places on the
table; the robot's ball (the URDF's ``ball_link``) is hand-guided into socket 0 and socket 1 about 30 times
each, in different arm configurations, and the joint angles are recorded:

  data/<robot>/<placement>/hole_0.csv, hole_1.csv    one configuration per line, joint angles [rad], no header
  data/<robot>/<placement>/comments.txt               (some) the operator's notes, kept as header comments

(panda_*: Franka Panda, kuka_14: KUKA iiwa 14, dinova_*: Kinova Gen3 lite on the DINOVA mobile base.)

Each robot becomes one ``<robot>.sockets.csv`` (placements numbered in name order, listed in the header;
source socket 0 -> socket 1, 1 -> 2). The seat's play is stated as 0.05 mm per coordinate: a printed ball in a
printed socket, an assumption (the source states none), which the fit's residual test checks.

    python scripts/convert_mukca2025.py SRC_DIR -o benchmarks/data/mukca2025 [--robots panda_2 kuka_14]

SRC_DIR is a checkout of the source repository. The source URDFs the data belong to (``urdf/panda.urdf``,
``urdf/iiwa14.urdf``) are copied beside them.
"""
from __future__ import annotations

import argparse
import hashlib
import sys
from pathlib import Path

import numpy as np

from rodlab.core.fileio import atomic_write_text

#: robot data folder -> (the source's URDF, joints)
ROBOTS = {"panda_2": ("panda.urdf", 7), "panda_3": ("panda.urdf", 7), "panda_6": ("panda.urdf", 7),
          "panda_7": ("panda.urdf", 7), "kuka_14": ("iiwa14.urdf", 7), "dinova_1": ("gen3lite.urdf", 6),
          "dinova_2": ("gen3lite.urdf", 6)}
DISTANCE_MM = 50.0
SEAT_SIGMA_MM = 0.05
HEADER = """# Ball-in-socket readings of {robot} (MUKCa artefact: two sockets {distance:g} mm apart), public data of
# G. Franzese, M. Spahn, M. Ramirez, github.com/platonics-delft/kinematics_calibration (MIT), converted by
# scripts/convert_mukca2025.py. q [deg] are the joints of the source's {urdf} (tip link ball_link).
# Placements (the source's folders): {placements}
# distance_mm: 1-2 = {distance:g}
# seat_sigma_mm: {seat:g}
"""


def _readings(folder: Path, n: int) -> list[np.ndarray]:
    out = []
    for hole in ("hole_0.csv", "hole_1.csv"):
        path = folder / hole
        if not path.is_file():
            raise SystemExit(f"{folder}: no {hole}; give a checkout of github.com/platonics-delft/kinematics_calibration")
        q = np.loadtxt(path, delimiter=",", ndmin=2)
        if q.shape[1] != n or not np.all(np.isfinite(q)):
            raise SystemExit(f"{path}: expected {n} finite joint angles per line, got shape {q.shape}")
        out.append(q)
    return out


def _operator_notes(folders: list[Path], robot: str, sums: list[str]) -> list[str]:
    """The source's comments.txt per placement as header comments (colons dropped: not ``# key: value`` lines)."""
    out = []
    for j, folder in enumerate(folders, start=1):
        path = folder / "comments.txt"
        note = " ".join(path.read_text(encoding="utf-8").split()).replace(":", " -") if path.is_file() else ""
        if note:
            out.append(f"# Operator's note, placement {j} ({folder.name}) - {note}\n")
            sums.append(f"{hashlib.sha256(path.read_bytes()).hexdigest()}  data/{robot}/{folder.name}/comments.txt")
    return out


def convert(src: Path, robot: str, out_dir: Path) -> tuple[Path, list[str]]:
    """One robot's folders to ``<robot>.sockets.csv``; returns the file and the sha256 of every source file."""
    urdf, n = ROBOTS[robot]
    folders = sorted(p for p in (src / "data" / robot).iterdir() if p.is_dir())
    if not folders:
        raise SystemExit(f"{src / 'data' / robot}: no placement folders")
    rows, sums = [], []
    for j, folder in enumerate(folders, start=1):
        for s, q in enumerate(_readings(folder, n), start=1):
            rows += [f"{j},{s}," + ",".join(f"{v:.6f}" for v in np.rad2deg(qi)) for qi in q]
            sums.append(f"{hashlib.sha256((folder / f'hole_{s - 1}.csv').read_bytes()).hexdigest()}  "
                        f"data/{robot}/{folder.name}/hole_{s - 1}.csv")
    head = HEADER.format(robot=robot, distance=DISTANCE_MM, urdf=urdf, seat=SEAT_SIGMA_MM,
                         placements=", ".join(f"{j}={f.name}" for j, f in enumerate(folders, start=1)))
    head += "".join(_operator_notes(folders, robot, sums))
    table = "placement,socket," + ",".join(f"q{i + 1}" for i in range(n))
    path = atomic_write_text(out_dir / f"{robot}.sockets.csv", head + table + "\n" + "\n".join(rows) + "\n")
    atomic_write_text(out_dir / urdf, (src / "urdf" / urdf).read_text(encoding="utf-8"))
    return path, sums


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("src", type=Path, help="checkout of github.com/platonics-delft/kinematics_calibration")
    ap.add_argument("-o", "--output", type=Path, default=Path("benchmarks/data/mukca2025"))
    ap.add_argument("--robots", nargs="+", default=list(ROBOTS), choices=list(ROBOTS))
    args = ap.parse_args(argv)
    args.output.mkdir(parents=True, exist_ok=True)
    sums = []
    for robot in args.robots:
        path, s = convert(args.src, robot, args.output)
        sums += s
        print(f"wrote {path}")
    print(f"wrote {atomic_write_text(args.output / 'SOURCE.sha256', chr(10).join(sums) + chr(10))}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
