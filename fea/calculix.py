"""Cross-check with CalculiX: write the same mesh, materials and tip loads as a ``ccx`` deck and run it.

C3D10 elements on the skfem P2 numbering (skfem, VTK and CalculiX share the tet10 node order), one
``*SOLID SECTION`` per part, the flange face clamped, the ball a ``*RIGID BODY`` with its reference node
at the ball centre loaded by unit forces (one ``*STEP`` per direction). Isotropic materials use
``*ELASTIC``; transversely-isotropic ones ``*ELASTIC, TYPE=ENGINEERING CONSTANTS`` with one
``*ORIENTATION`` per element (axis 1 = local tube axis).
"""
from __future__ import annotations

import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import numpy as np

from rodlab.core.design import RodDesign
from rodlab.core.enums import Part
from rodlab.core.units import gpa_to_mpa

from .elasticity import NU23_DEFAULT, local_frames
from .stiffness_assembly import scalar_basis
from .errors import FeaError

__all__ = ["ccx_available", "write_deck", "run_ccx_compliance"]


def ccx_available() -> str | None:
    """Path of the ``ccx`` executable (Debian package ``calculix-ccx``), or None."""
    return shutil.which("ccx")


def write_deck(design: RodDesign, rod_mesh, path: str | Path) -> Path:
    """Write the CalculiX input deck; returns its path (``.inp``)."""
    basis = scalar_basis(rod_mesh.mesh)
    X = basis.doflocs.T
    ed = basis.element_dofs.T + 1                                    # 1-based node numbers, (ne, 10)
    n_nodes = X.shape[0]
    ref, rot = n_nodes + 1, n_nodes + 2
    out = ["*HEADING", f"rodlab cross-check of rod {design.name}", "*NODE"]
    out += [f"{i + 1}, {x:.10g}, {y:.10g}, {z:.10g}" for i, (x, y, z) in enumerate(X)]
    out += [f"{ref}, 0, 0, 0", f"{rot}, 0, 0, 0"]
    for k, part in enumerate(rod_mesh.parts):
        els = np.nonzero(rod_mesh.part_index == k)[0]
        out.append(f"*ELEMENT, TYPE=C3D10, ELSET={part.value}")
        out += [f"{e + 1}, " + ", ".join(str(n) for n in ed[e]) for e in els]
    fixed = basis.get_dofs(rod_mesh.flange_facets).all() + 1
    out.append("*NSET, NSET=FLANGE")
    out += [", ".join(str(n) for n in fixed[i:i + 12]) for i in range(0, fixed.size, 12)]
    ball = np.unique(basis.element_dofs[:, rod_mesh.elements_of(Part.BALL)]) + 1
    out.append("*NSET, NSET=BALL")
    out += [", ".join(str(n) for n in ball[i:i + 12]) for i in range(0, ball.size, 12)]
    out.append("*NSET, NSET=REF")
    out.append(str(ref))
    for k, part in enumerate(rod_mesh.parts):
        mat = design.material_of(part)
        name = f"M_{part.value}"
        if mat.is_isotropic:
            out += [f"*MATERIAL, NAME={name}", "*ELASTIC", f"{gpa_to_mpa(mat.E_GPa):.6g}, {mat.nu:.6g}",
                    f"*SOLID SECTION, ELSET={part.value}, MATERIAL={name}"]
        else:
            E1, E2, G12 = gpa_to_mpa(mat.E_GPa), gpa_to_mpa(mat.E_t_GPa), gpa_to_mpa(mat.G_axial_GPa)
            G23 = E2 / (2 * (1 + NU23_DEFAULT))
            out += [f"*MATERIAL, NAME={name}", "*ELASTIC, TYPE=ENGINEERING CONSTANTS",
                    f"{E1:.6g}, {E2:.6g}, {E2:.6g}, {mat.nu:.6g}, {mat.nu:.6g}, {NU23_DEFAULT:.6g}, {G12:.6g}, "
                    f"{G12:.6g},", f"{G23:.6g}"]
            els = rod_mesh.elements_of(part)
            R = local_frames(rod_mesh.tube_axis[els])
            for e, Re in zip(els, R):
                a, b = Re[:, 0], Re[:, 1]
                out += [f"*ELSET, ELSET=E{e + 1}", str(e + 1),
                        f"*ORIENTATION, NAME=O{e + 1}", ", ".join(f"{v:.9g}" for v in np.concatenate([a, b])),
                        f"*SOLID SECTION, ELSET=E{e + 1}, MATERIAL={name}, ORIENTATION=O{e + 1}"]
    out += [f"*RIGID BODY, NSET=BALL, REF NODE={ref}, ROT NODE={rot}", "*BOUNDARY", "FLANGE, 1, 3, 0.0"]
    for j in range(3):
        out += ["*STEP", "*STATIC", "*CLOAD, OP=NEW", f"{ref}, {j + 1}, 1.0", "*NODE PRINT, NSET=REF", "U",
                "*END STEP"]
    p = Path(path)
    p.write_text("\n".join(out) + "\n")
    return p


def run_ccx_compliance(design: RodDesign, rod_mesh, workdir: str | Path | None = None,
                       timeout_s: float = 600.0) -> np.ndarray:
    """Run CalculiX on the deck; return its C_F [mm/N], shape=(3, 3)."""
    exe = ccx_available()
    if exe is None:
        raise FeaError("CalculiX (ccx) is not installed: apt-get install calculix-ccx", key="ccx")
    with tempfile.TemporaryDirectory(prefix="rodlab-ccx-") as tmp:
        wd = Path(workdir or tmp)
        write_deck(design, rod_mesh, wd / "rod.inp")
        r = subprocess.run([exe, "-i", "rod"], cwd=wd, capture_output=True, text=True, timeout=timeout_s,
                           env={"OMP_NUM_THREADS": "2", "PATH": "/usr/bin:/bin"})
        dat = wd / "rod.dat"
        if r.returncode != 0 or not dat.exists():
            raise FeaError(f"ccx failed (exit {r.returncode}): {(r.stdout + r.stderr)[-400:]}", key="ccx")
        rows = []
        for line in dat.read_text().splitlines():
            m = re.match(r"^\s*\d+\s+(\S+)\s+(\S+)\s+(\S+)\s*$", line)
            if m:
                rows.append([float(v) for v in m.groups()])
    if len(rows) != 3:
        raise FeaError(f"expected 3 displacement records in the ccx output, found {len(rows)}", key="ccx")
    return np.array(rows).T
