"""geometry/mesh_cache.py: the per-user mesh cache of ``rodlab fea``."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from rodlab.core.design_io import resolve_design

pytest.importorskip("gmsh")
from rodlab.geometry import MeshCache, mesh_rod  # noqa: E402
from rodlab.geometry import mesh_cache  # noqa: E402


def _counting():
    calls = []

    def mesher(design, **kw):
        calls.append(kw)
        return mesh_rod(design, **kw)
    return mesher, calls


def test_the_same_design_and_size_mesh_once_and_come_back_equal(tmp_path):
    mesher, calls = _counting()
    cache = MeshCache(mesher, tmp_path)
    d = resolve_design("rod1")
    a = cache(d, size_mm=30.0, grading=None, half=True)
    b = cache(d, size_mm=30.0, grading=None, half=True)
    assert len(calls) == 1 and (cache.hits, cache.misses) == (1, 1)
    assert b.sha256 == a.sha256 and np.array_equal(b.mesh.t, a.mesh.t) and np.array_equal(b.tube_axis, a.tube_axis)
    assert b.is_half and b.parts == a.parts


def test_any_change_the_mesh_depends_on_meshes_again(tmp_path):
    mesher, calls = _counting()
    cache = MeshCache(mesher, tmp_path)
    d = resolve_design("rod1")
    cache(d, size_mm=30.0, grading=None, half=True)
    cache(d, size_mm=30.0, grading=None, half=False)                           # whole rod
    cache(d, size_mm=31.0, grading=None, half=True)                            # size
    cache(dataclasses.replace(d, L1_mm=d.L1_mm + 1.0), size_mm=30.0, grading=None, half=True)   # a dimension
    assert len(calls) == 4 and cache.hits == 0


def test_a_damaged_entry_is_meshed_again_and_replaced(tmp_path):
    mesher, calls = _counting()
    cache = MeshCache(mesher, tmp_path)
    d = resolve_design("rod1")
    cache(d, size_mm=30.0, grading=None, half=True)
    entry = next(tmp_path.glob("*.pickle"))
    entry.write_bytes(b"not a pickle")
    rm = cache(d, size_mm=30.0, grading=None, half=True)
    assert len(calls) == 2 and rm.is_half
    assert MeshCache(mesher, tmp_path)(d, size_mm=30.0, grading=None, half=True).sha256 == rm.sha256
    assert len(calls) == 2                                                        # the replaced entry is read


def test_the_folder_follows_the_environment(monkeypatch, tmp_path):
    monkeypatch.setenv("RODLAB_CACHE_DIR", str(tmp_path))
    assert mesh_cache.cache_folder() == tmp_path / "meshes"
    monkeypatch.setenv("RODLAB_CACHE_DIR", "off")
    assert mesh_cache.cache_folder() is None
    mesher, calls = _counting()
    cache = MeshCache(mesher)
    d = resolve_design("rod1")
    cache(d, size_mm=30.0, grading=None, half=True)
    cache(d, size_mm=30.0, grading=None, half=True)
    assert len(calls) == 2 and not list(tmp_path.rglob("*.pickle"))
