"""geometry/mesh_cache.py: the per-user mesh cache of ``rodlab fea``."""
from __future__ import annotations

import dataclasses
import os

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


def test_a_read_only_entry_still_serves_and_another_users_entry_is_not_read(tmp_path, monkeypatch):
    mesher, calls = _counting()
    cache = MeshCache(mesher, tmp_path)
    d = resolve_design("rod1")
    cache(d, size_mm=30.0, grading=None, half=True)
    entry = next(tmp_path.glob("*.pickle"))

    def no_utime(*a, **k):
        raise PermissionError("read-only")
    monkeypatch.setattr(os, "utime", no_utime)
    assert cache(d, size_mm=30.0, grading=None, half=True).is_half and len(calls) == 1     # a hit all the same
    monkeypatch.setattr(os, "getuid", lambda: entry.stat().st_uid + 1)
    cache(d, size_mm=30.0, grading=None, half=True)
    assert len(calls) == 2                                                       # not another user's pickle


def test_the_key_holds_the_mesher_source_and_versions():
    key_text = mesh_cache._code_and_versions()
    assert len(key_text) == 64
    d = resolve_design("rod1")
    cache = MeshCache(mesh_rod, None)
    assert cache.key(d, size_mm=30.0, half=True) != cache.key(d, size_mm=30.0, half=False)
    mesh_cache._code_and_versions.cache_clear()
    try:
        original = mesh_cache._CORE_SOURCES
        mesh_cache._CORE_SOURCES = original[:-1]                               # as if a source had changed
        assert mesh_cache._code_and_versions() != key_text
    finally:
        mesh_cache._CORE_SOURCES = original
        mesh_cache._code_and_versions.cache_clear()
