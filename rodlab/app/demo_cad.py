"""The demo's CAD stage in a second process, beside the FEA and everything after it.

Nothing in the demo reads the CAD assembly (the solid FEA meshes the rod with gmsh's own OpenCASCADE kernel), and
its ~4-5 s (build123d's import ~2.4 s, the four views ~1.5 s with matplotlib) are single-threaded Python, so
on 2 cores they overlap the other stages: ``rodlab demo`` ~3 s faster (docs/benchmarks/speed.md). The child is
this module's :func:`main` run as ``python -c ... DESIGN OUT_DIR`` (:data:`_CHILD`) with one BLAS/OpenMP thread (its
work is OpenCASCADE and matplotlib; an idle second thread would only spin against the main process); it
writes ``rod.step``, ``mass.json`` and the ``view_*.png`` files (each atomically) and prints one JSON line
with the numbers the run summary needs. A failure in it is raised in the demo with the child's own message.
"""
from __future__ import annotations

import json
import logging
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import rodlab.geometry as geometry

from ..core.cluster import ONE_THREAD_ENV
from ..core.design_io import resolve_design
from ..core.errors import RodlabError

__all__ = ["CadStage", "CadJob", "start_cad_job"]

log = logging.getLogger(__name__)

@dataclass(frozen=True)
class CadStage:
    """What the CAD stage made: ``parts`` solids, their total ``mass_kg`` [kg], the ``views`` PNG paths (inside
    the CAD folder) and the child's wall time ``seconds`` [s] (started to finished, by the clock: the stage
    overlaps the others)."""

    parts: int
    mass_kg: float
    views: tuple[Path, ...]
    seconds: float

    def __post_init__(self) -> None:
        if self.parts < 1 or not self.mass_kg > 0:
            raise ValueError(f"CadStage: parts {self.parts} and mass_kg {self.mass_kg} must be positive")


class CadJob:
    """A running CAD stage (see :func:`start_cad_job`); :meth:`result` waits for it, :meth:`cancel` stops it."""

    def __init__(self, proc: subprocess.Popen, out_dir: Path, started: float, out, err) -> None:
        self._proc, self.out_dir, self._started = proc, out_dir, started
        self._out, self._err = out, err                  # temporary files: a chatty child never blocks on a pipe

    def result(self) -> CadStage:
        """Wait for the child; its :class:`CadStage` (its stderr relayed to the log), or :class:`RodlabError` with
        the child's message."""
        self._proc.wait()
        out, err = self._read()
        if self._proc.returncode != 0:
            tail = "\n".join(err.strip().splitlines()[-12:]) or f"exit status {self._proc.returncode}"
            raise RodlabError(f"the demo's CAD stage (building {self.out_dir}) failed:\n{tail}")
        for line in err.strip().splitlines():
            log.warning("CAD stage: %s", line)
        try:
            made = json.loads(out.strip().splitlines()[-1])
            return CadStage(int(made["parts"]), float(made["mass_kg"]), tuple(Path(v) for v in made["views"]),
                            float(made["finished"]) - self._started)
        except (ValueError, KeyError, IndexError, TypeError) as e:
            raise RodlabError(f"the demo's CAD stage (building {self.out_dir}) gave no summary: {out[-300:]!r}; "
                              f"build it alone with `rodlab cad` to see why") from e

    def cancel(self) -> None:
        """Stop the child if it still runs (the demo failed or was interrupted)."""
        if self._proc.poll() is None:
            self._proc.kill()
            self._proc.wait()
        self._read()

    def _read(self) -> tuple[str, str]:
        """The child's stdout and stderr ("" once read: the temporary files are then closed, so removed)."""
        return self._drain(self._out), self._drain(self._err)

    @staticmethod
    def _drain(f) -> str:
        if f.closed:
            return ""
        f.seek(0)
        with f:
            return f.read()


#: the child's start: this module's main with the current folder off the import path (``python -m`` would put it
#: first, so a ``rodlab/`` folder where the user stands would be imported by the child and not the parent)
_CHILD = "import sys; sys.path.pop(0); from rodlab.app.demo_cad import main; sys.exit(main(sys.argv[1:]))"


def start_cad_job(design: str, out_dir: str | Path) -> CadJob:
    """Start building the CAD of the built-in or file ``design`` into ``out_dir`` in a second process."""
    out_dir = Path(out_dir)
    env = {**os.environ, **ONE_THREAD_ENV}
    out, err = tempfile.TemporaryFile("w+"), tempfile.TemporaryFile("w+")
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, str(design), str(out_dir)], env=env,
                            stdin=subprocess.DEVNULL, stdout=out, stderr=err, text=True)
    return CadJob(proc, out_dir, time.time(), out, err)


def build_into(design: str, out_dir: Path) -> dict:
    """The stage itself (in the child): STEP, mass.json and the views of ``design`` in ``out_dir``."""
    cad = geometry.build_cad(resolve_design(design))
    cad.export_step(out_dir / "rod.step")
    cad.write_mass_json(out_dir / "mass.json")
    views = geometry.render_views(cad, out_dir)
    return {"parts": len(cad.solids), "mass_kg": cad.total_mass_properties().mass_kg,
            "views": [str(p) for p in views], "finished": time.time()}


def main(argv: list[str]) -> int:
    """``python -m rodlab.app.demo_cad DESIGN OUT_DIR``: the stage; one JSON line on stdout; exit 1 with the
    message on stderr on failure."""
    if len(argv) != 2:
        print("usage: python -m rodlab.app.demo_cad DESIGN OUT_DIR", file=sys.stderr)
        return 2
    try:
        made = build_into(argv[0], Path(argv[1]))
    except (RodlabError, OSError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 1
    print(json.dumps(made))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
