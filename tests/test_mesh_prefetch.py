"""geometry/mesh_prefetch.py and fea/mesh_request.py: ``rodlab fea --model solid`` meshes in the background while
the solver loads, and the mesh it starts is the one the solid model asks for."""
from __future__ import annotations

import threading

import pytest

from rodlab.core.design_io import resolve_design
from rodlab.fea.errors import FeaError
from rodlab.fea.mesh_request import DEFAULT_GRADING, default_solid_size_mm, solid_mesh_request
from rodlab.geometry.errors import GeometryError
from rodlab.geometry.mesh_prefetch import MeshPrefetch


class _Recorder:
    """A mesher that records its calls and the thread each ran on; ``gate`` holds the first call back."""

    def __init__(self, fail: Exception | None = None):
        self.calls, self.threads = [], []
        self.gate = threading.Event()
        self.fail = fail

    def __call__(self, design, **kw):
        self.gate.wait(10)
        self.calls.append(kw)
        self.threads.append(threading.current_thread().name)
        if self.fail is not None:
            raise self.fail
        return ("mesh", design.name, tuple(sorted(kw.items())))


class _Stop(Exception):
    pass


def test_the_prefetched_mesh_is_the_one_asked_for_and_made_in_the_background():
    d = resolve_design("rod1")
    inner = _Recorder()
    pre = MeshPrefetch(inner, d, size_mm=12.0, grading=DEFAULT_GRADING, half=True)
    assert inner.calls == []                                 # held at the gate: started, not finished
    inner.gate.set()
    got = pre(d, size_mm=12.0, grading=DEFAULT_GRADING, half=True)
    assert got == ("mesh", d.name, (("grading", DEFAULT_GRADING), ("half", True), ("size_mm", 12.0)))
    assert len(inner.calls) == 1 and inner.threads[0] != threading.current_thread().name
    # anything else (another size, or the same request again) is meshed by the wrapped mesher, here
    pre(d, size_mm=18.0, grading=DEFAULT_GRADING, half=True)
    pre(d, size_mm=12.0, grading=DEFAULT_GRADING, half=True)
    assert [c["size_mm"] for c in inner.calls] == [12.0, 18.0, 12.0]
    assert inner.threads[1:] == [threading.current_thread().name] * 2


def test_an_error_of_the_background_mesh_reaches_the_caller_unchanged():
    d = resolve_design("rod1")
    inner = _Recorder(GeometryError("the mesh has inverted elements; use a smaller --size", key="size"))
    inner.gate.set()
    pre = MeshPrefetch(inner, d, size_mm=12.0, grading=None, half=True)
    with pytest.raises(GeometryError, match="inverted elements") as ei:
        pre(d, size_mm=12.0, grading=None, half=True)
    assert ei.value.key == "size"


def test_the_request_is_what_the_solid_model_asks_its_mesher_for():
    """If the two drifted apart, the background mesh would be wasted and the solve would mesh again."""
    from rodlab.fea.compute import solid_compliance
    for name, size, symmetry in (("rod1", None, True), ("rod4", 9.0, False)):
        d = resolve_design(name)
        seen = []

        def mesher(design, **kw):
            seen.append(kw)
            raise _Stop

        with pytest.raises(_Stop):
            solid_compliance(d, mesher, size_mm=size, symmetry=symmetry)
        assert seen == [solid_mesh_request(d, size, symmetry=symmetry).kwargs]
    assert solid_mesh_request(resolve_design("rod1")).size_mm == default_solid_size_mm(resolve_design("rod1"))


@pytest.mark.parametrize("size, match", [(float("nan"), "positive number"), (-2.0, "positive number"),
                                         ("abc", "positive number"), (0.3, "M DOFs")])
def test_a_bad_size_is_refused_before_any_mesh(size, match):
    with pytest.raises(FeaError, match=match) as ei:
        solid_mesh_request(resolve_design("rod1"), size)
    assert ei.value.key == "size"
