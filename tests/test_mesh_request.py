"""fea/mesh_request.py: the mesh the solid model asks for, decided and checked without the solver's imports."""
from __future__ import annotations

import pytest

from rodlab.core.design_io import resolve_design
from rodlab.fea.errors import FeaError
from rodlab.fea.mesh_request import default_solid_size_mm, solid_mesh_request


class _Stop(Exception):
    pass


def test_the_request_is_what_the_solid_model_asks_its_mesher_for():
    """The request and the solid model's call of its mesher are one: the keywords match."""
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
