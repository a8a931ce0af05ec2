"""build123d imported without scikit-learn (geometry.cadlib), and build123d's one use of it still works."""
from __future__ import annotations

import subprocess
import sys

import pytest

pytest.importorskip("build123d", reason="the cad extra")

_CHECK = r"""
import sys
from rodlab.geometry.cadlib import build123d
bd = build123d()
assert "sklearn" not in sys.modules and "sklearn.cluster" not in sys.modules, "scikit-learn was imported"
box = bd.Solid.make_box(10, 20, 30)
assert abs(box.volume - 6000.0) < 1e-6
import build123d.brep_from_stl as stl
model = stl.DBSCAN(eps=0.5, min_samples=2)          # the stand-in: scikit-learn's own DBSCAN, imported now
import sklearn.cluster
assert type(model) is sklearn.cluster.DBSCAN and sys.modules["sklearn.cluster"] is sklearn.cluster
assert list(model.fit([[0.0], [0.1], [5.0], [5.1]]).labels_) == [0, 0, 1, 1]
print("ok")
"""


def test_build123d_without_scikit_learn_until_it_is_needed():
    out = subprocess.run([sys.executable, "-c", _CHECK], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "ok"


_ALREADY = r"""
import sys
import sklearn.cluster
from rodlab.geometry.cadlib import build123d
assert "build123d" not in sys.modules
build123d()
import build123d.brep_from_stl as stl
assert stl.DBSCAN is sklearn.cluster.DBSCAN             # scikit-learn already there: nothing stood in
print("ok")
"""


def test_nothing_is_stood_in_where_scikit_learn_is_imported():
    out = subprocess.run([sys.executable, "-c", _ALREADY], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
