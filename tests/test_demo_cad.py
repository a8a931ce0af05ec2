"""The demo's CAD stage in a second process: its failure is the demo's clear error, it is stopped when the demo
fails, and its numbers are those of the CAD built in this process."""
from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest

import rodlab.app.pipeline as pipeline
from rodlab.app.demo_cad import CadStage, start_cad_job
from rodlab.core.errors import RodlabError

cad = pytest.importorskip("build123d", reason="the cad extra")


def test_a_failing_child_is_the_demos_error_with_its_message(tmp_path):
    job = start_cad_job("no_such_rod", tmp_path / "cad")
    with pytest.raises(RodlabError, match="CAD stage .* failed:\n.*no_such_rod: no such file or built-in design"):
        job.result()
    assert not (tmp_path / "cad").exists()


def test_the_child_imports_the_parents_rodlab_not_one_in_the_current_folder(tmp_path, monkeypatch):
    """`python -m` would put the current folder first on the child's path (review): a `rodlab/` folder there
    (a source checkout beside a non-editable install) must not be what the child imports."""
    shadow = tmp_path / "rodlab"
    shadow.mkdir()
    (shadow / "__init__.py").write_text("raise ImportError('the shadow package was imported')\n")
    monkeypatch.chdir(tmp_path)
    with pytest.raises(RodlabError, match="no_such_rod: no such file or built-in design"):
        start_cad_job("no_such_rod", tmp_path / "cad").result()


def test_the_child_builds_what_this_process_builds(tmp_path):
    import rodlab.geometry as geometry
    from rodlab.core.design_io import resolve_design
    made = start_cad_job("rod2", tmp_path / "cad").result()
    here = geometry.build_cad(resolve_design("rod2"))
    assert made.parts == len(here.solids)
    assert made.mass_kg == pytest.approx(here.total_mass_properties().mass_kg, rel=1e-9)
    assert [p.name for p in made.views] == ["view_iso.png", "view_xz.png", "view_xy.png", "view_yz.png"]
    assert all(p.stat().st_size > 10_000 for p in made.views)
    assert (tmp_path / "cad" / "rod.step").stat().st_size > 0 and (tmp_path / "cad" / "mass.json").exists()
    assert 0 < made.seconds < 600


def test_cancel_stops_a_running_child(tmp_path):
    job = start_cad_job("rod1", tmp_path / "cad")
    t0 = time.perf_counter()
    job.cancel()
    assert time.perf_counter() - t0 < 5
    assert job._proc.poll() is not None


def test_cad_stage_checks_its_numbers():
    with pytest.raises(ValueError, match="parts 0"):
        CadStage(0, 1.0, (), 1.0)


class _FakeJob:
    cancelled = False

    def cancel(self):
        _FakeJob.cancelled = True


def test_a_failing_stage_stops_the_cad_child(tmp_path, monkeypatch):
    def boom(self):
        raise RuntimeError("the rig stage failed")
    monkeypatch.setattr(pipeline, "start_cad_job", lambda design, out: _FakeJob())
    monkeypatch.setattr(pipeline._DemoRun, "stage_rig", boom)
    monkeypatch.setattr(pipeline._DemoRun, "stage_fea", lambda self: None)
    with pytest.raises(RuntimeError, match="rig stage failed"):
        pipeline.run_demo(tmp_path, sweep_grid=(np.array([300.0]), np.array([450.0])))
    assert _FakeJob.cancelled
    assert not (tmp_path / "run.json").exists()


def _cad_children(pid: int) -> list:
    psutil = pytest.importorskip("psutil")
    try:
        return [c for c in psutil.Process(pid).children(recursive=True) if "demo_cad" in " ".join(c.cmdline())]
    except psutil.NoSuchProcess:
        return []


def test_a_killed_demo_stops_its_cad_child(tmp_path):
    """``kill`` (SIGTERM) ends the demo as Ctrl-C does: the CAD child is stopped, exit 130, "interrupted"."""
    psutil = pytest.importorskip("psutil")
    proc = subprocess.Popen([sys.executable, "-m", "rodlab", "demo", "-o", str(tmp_path / "demo")],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        children = []
        while not children and proc.poll() is None and time.monotonic() < deadline:
            time.sleep(0.1)
            children = _cad_children(proc.pid)
        assert children, "the demo's CAD child never started"
        proc.terminate()
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130 and "interrupted" in err, err
    gone, alive = psutil.wait_procs(children, timeout=10)
    assert not alive
