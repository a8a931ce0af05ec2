"""A simulated replicate (:func:`calibrate.predict.simulate_replicate`) as the contract's files, so the same
draws can be calibrated end to end by ``rodlab calibrate`` — the check that the in-memory predictor gives what
users get from files."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from rodlab.core.compliance import RodCompliance, write_compliance
from rodlab.core.fileio import atomic_write_json, atomic_write_text

from .campaign import Fixture
from .predict import SimulatedReplicate

__all__ = ["write_replicate"]


def write_replicate(sim: SimulatedReplicate, fixture: Fixture, reference: RodCompliance, out_dir) -> dict:
    """Write ``campaign.csv``, ``fixture.json``, ``validation.csv`` and ``<method>.compliance.json`` per method
    into ``out_dir``; returns {name: path}."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    c = sim.campaign
    n = c.q_rad.shape[1]
    point = np.zeros(len(c.group), int)
    for j in np.unique(c.group):
        m = c.group == j
        point[m] = np.arange(1, int(m.sum()) + 1)
    rows = [f"{int(j)},{int(i)}," + ",".join(f"{v:.6f}" for v in np.rad2deg(q)) + ","
            + ",".join(f"{v:.6f}" for v in x) for j, i, q, x in zip(c.group, point, c.q_rad, c.x_D_mm)]
    paths = {"campaign": atomic_write_text(out / "campaign.csv", "position,point," + ",".join(
        f"q{i + 1}" for i in range(n)) + ",x_mm,y_mm,z_mm\n" + "\n".join(rows) + "\n")}
    paths["fixture"] = atomic_write_json(out / "fixture.json", {
        "format": "rodlab.fixture/1", "world_position": int(fixture.world_position),
        "positions": {str(j): [round(float(v), 9) for v in p] for j, p in c.recorded_poses.items()},
        "contact_force_N": [float(v) for v in fixture.force_D_N]})
    p = sim.points
    lines = ["# tool_mm: " + ", ".join(f"{v:g}" for v in p.tool_mm), f"# rod_mass_kg: {p.rod_mass_kg:g}",
             "# rod_com_T_mm: " + ", ".join(f"{v:g}" for v in p.rod_com_T_mm),
             ",".join(f"q{i + 1}" for i in range(n)) + ",x_mm,y_mm,z_mm"]
    lines += [",".join(f"{v:.6f}" for v in q) + "," + ",".join(f"{v:.6f}" for v in x)
              for q, x in zip(p.q_deg, p.x_W_mm)]
    paths["validation"] = atomic_write_text(out / "validation.csv", "\n".join(lines) + "\n")
    for m, file in sim.files.items():
        rod = file if file is not None else RodCompliance.none_like(reference)
        paths[str(m)] = write_compliance(rod, out / f"{m}.compliance.json")
    return paths
