"""A researcher's trial with the paper's rods (2026-11-29, helper-53): a rod and its as-built design studied side by
side, the as-built's measurement not counted twice, and out-of-range r_rod named."""
from __future__ import annotations

from rodlab.app.cli import main
from rodlab.app.study.designs import R_PRIOR_AS_BUILT, R_PRIOR_COMPOSITE, list_candidates, r_prior_of
from rodlab.app.study.family import _family_key
from rodlab.core.design_io import load_design, resolve_design


def _as_built(tmp_path):
    """rod 1# measured 1.23x softer, through `rig simulate`, `rig fit` and `update` (the design keeps its name)."""
    sim, rec, meas, out = (tmp_path / n for n in ("rod1.frame.json", "r1.rig.csv", "r1.meas.json", "rod1.asbuilt.rod.toml"))
    assert main(["fea", "rod1", "--model", "frame", "-o", str(sim)]) == 0
    assert main(["rig", "simulate", "--sim", str(sim), "--effect", "compliance_scale:r=1.23", "--repeats", "2",
                 "--hold-s", "4", "-o", str(rec)]) == 0
    assert main(["rig", "fit", str(rec), "--sim", str(sim), "-o", str(meas)]) == 0
    assert main(["update", "rod1", "--measured", str(meas), "-o", str(out)]) == 0
    return load_design(out)


def test_a_rod_and_its_as_built_design_are_two_candidates_and_two_families(tmp_path):
    """They share the name 1#: the study had keyed both by it (one family, one label), and the nominal rod failed
    with "1# is not a member of 1#'s family"."""
    rod1, built = resolve_design("rod1"), _as_built(tmp_path)
    assert built.name == rod1.name
    labels = [c.label for c in list_candidates([rod1, built])]
    assert labels == ["1# (rod1.rod.toml)", "1# (rod1.asbuilt.rod.toml)"]
    assert _family_key(rod1) != _family_key(built)                 # other moduli: another solid run
    assert _family_key(rod1) == _family_key(resolve_design("rod1"))
    assert r_prior_of(built) == R_PRIOR_AS_BUILT and r_prior_of(rod1) == R_PRIOR_COMPOSITE


def test_an_r_rod_beyond_the_papers_rods_is_remarked(tmp_path, capsys):
    sim, rec, meas = tmp_path / "rod1.frame.json", tmp_path / "soft.rig.csv", tmp_path / "soft.meas.json"
    assert main(["fea", "rod1", "--model", "frame", "-o", str(sim)]) == 0
    for r, says in ((3.5, "beyond the paper's softest rod"), (0.8, "stiffer than its simulation")):
        assert main(["rig", "simulate", "--sim", str(sim), "--effect", f"compliance_scale:r={r}", "--repeats", "2",
                     "--hold-s", "4", "-o", str(rec)]) == 0
        capsys.readouterr()
        assert main(["rig", "fit", str(rec), "--sim", str(sim), "-o", str(meas)]) == 0
        assert says in capsys.readouterr().out
    from rodlab.app.cli.cmd_study import _range2
    assert _range2("3.5:3.5", "r-prior-composite") == (3.5, 3.5)
    assert "beyond the paper's measured rods" in capsys.readouterr().err
    _range2("1.23:2.30", "r-prior-composite")
    assert capsys.readouterr().err == ""


def test_info_names_a_rod_softer_than_the_papers(tmp_path, capsys):
    """The contract's example tube (cfrp 25 x 2) gives a c_rod 3.5x steel 4#'s with no hint (a paper trial)."""
    design = tmp_path / "soft.rod.toml"
    design.write_text('format = "rodlab.rod/1"\nname = "soft"\nL1_mm = 300.0\nL2_mm = 450.0\ngamma_deg = 90.0\n'
                      '[tube]\nmaterial = "cfrp"\nouter_diameter_mm = 25.0\nwall_mm = 2.0\n'
                      '[ball]\nmaterial = "alumina"\ndiameter_mm = 30.0\n')
    assert main(["info", str(design)]) == 0
    assert "softer than every rod the paper measured" in capsys.readouterr().out
    assert main(["info", "rod6"]) == 0
    assert "softer than every rod" not in capsys.readouterr().out


def test_a_rod_and_its_as_built_twin_of_one_mass_recommend_the_more_accurate():
    """The lightest within the band: between designs of the same mass (a rod and its as-built design) the more
    accurate one, not the first listed."""
    import pandas as pd

    from rodlab.app.study.table import recommend
    rows = []
    for design, mean in (("1# (rod1.rod.toml)", 0.053), ("1# (rod1.asbuilt.rod.toml)", 0.044)):
        rows.append({"design": design, "status": "ok", "method": "meas", "mean_mm": mean, "mean_p05_mm": mean - 0.01,
                     "mean_p95_mm": mean + 0.03, "mass_kg": 1.333, "c_rod_um": 44.0, "L1_mm": 300.0, "L2_mm": 450.0,
                     "nominal_mean_mm": 1.7})
    assert recommend(pd.DataFrame(rows)).design == "1# (rod1.asbuilt.rod.toml)"
