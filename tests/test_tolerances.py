"""Design tolerances ([tolerances], documented defaults), the rod as built (dotted keys set), compliance
sensitivities, the methods' accuracy against the solid references, and the as-built file writer."""
import numpy as np
import pytest

from rodlab import calc_rod_compliance, load_design, resolve_design
from conftest import legacy_design
from rodlab.core.design_edit import edited_design_text, write_edited_design
from rodlab.core.errors import DesignError, RodlabError
from rodlab.core.sensitivity import METHOD_ACCURACY, compliance_sensitivity, with_values
from rodlab.core.tolerances import design_tolerances, design_value

TOML = """format = "rodlab.rod/1"
name = "t"
L1_mm = 300.0
L2_mm = 450.0
gamma_deg = 90.0
[tube]   # a comment that must survive
material = "cfrp_tube"
outer_diameter_mm = 25.0
wall_mm = 2.0
[materials.cfrp_tube]
E_GPa = 100.0
G_GPa = 10.0
nu = 0.30
density_kg_m3 = 1550.0
"""


def _write(tmp_path, extra=""):
    p = tmp_path / "t.rod.toml"
    p.write_text(TOML + extra)
    return p


def test_tolerances_file_over_defaults(tmp_path):
    d = load_design(_write(tmp_path, '[tolerances]\n"tube.outer_diameter_mm" = 0.1\n'
                                     '"materials.cfrp_tube.E_GPa" = "8%"\n"tube.wall_mm" = 0\n'))
    tol = {p.key: p for p in design_tolerances(d)}
    assert tol["tube.outer_diameter_mm"].sigma == pytest.approx(0.1) and tol["tube.outer_diameter_mm"].source == "file"
    assert tol["materials.cfrp_tube.E_GPa"].sigma == pytest.approx(8.0)
    assert tol["materials.cfrp_tube.G_GPa"].sigma == pytest.approx(2.0)      # laminate default 20 %
    assert "tube.wall_mm" not in tol                                          # 0 removes a default


def test_bond_tolerances(tmp_path):
    """Bonds get the default bending tolerance unless the file states one (absolute only, a known place)."""
    from rodlab.core.tolerances import BOND_SD, bond_tolerances
    d = load_design(_write(tmp_path, '[tolerances]\n"joints.ring_1.s_bend_rad_per_Nm" = 5e-6\n'
                                     '"joints.pipe_II.s_bend_rad_per_Nm" = 0\n'))
    assert bond_tolerances(d) == {"flange_clamp": BOND_SD, "ring_1": 5e-6}
    with pytest.raises(DesignError, match="Did you mean `ring_1`"):
        load_design(_write(tmp_path, '[tolerances]\n"joints.ring1.s_bend_rad_per_Nm" = 5e-6\n'))
    with pytest.raises(DesignError, match="absolute"):
        load_design(_write(tmp_path, '[tolerances]\n"joints.ring_1.s_bend_rad_per_Nm" = "5%"\n'))


def test_metal_defaults_are_tight():
    tol = {p.key: p.relative for p in design_tolerances(legacy_design("rod4"))}
    assert tol["materials.steel_304.E_GPa"] == pytest.approx(0.03)
    assert not any(k.endswith("G_GPa") for k in tol)                          # isotropic: G follows E


@pytest.mark.parametrize("entry, message", [
    ('"materials.cfrp.E_GPa" = "5%"', "Did you mean `materials.cfrp_tube.E_GPa`"),
    ('"tube.wall_mm" = "5 percent"', "percentage"),
    ('"tube.wall_mm" = -1', "number >= 0"),
])
def test_bad_tolerance_named_with_line(tmp_path, entry, message):
    with pytest.raises(DesignError) as e:
        load_design(_write(tmp_path, "[tolerances]\n" + entry + "\n"))
    assert message in str(e.value) and "t.rod.toml, line 16" in str(e.value)


def test_with_values_is_the_rod_as_built():
    d = legacy_design("rod1")
    soft = with_values(d, {"materials.cfrp_tube.E_GPa": 80.0, "tube.outer_diameter_mm": 26.0})
    assert design_value(soft, "materials.cfrp_tube.E_GPa") == 80.0
    assert soft.pipe_I.outer_diameter_mm == soft.pipe_II.outer_diameter_mm == 26.0
    with pytest.raises(DesignError, match="no numeric key"):
        with_values(d, {"tube.od": 1.0})


def test_sensitivity_matches_the_closed_form_scaling():
    """C_F of the closed form is EI-proportional in bending: d ln c11 / d ln E = -1 exactly on a rod whose
    members are all the one material (rod 1#'s bend is steel: only the tube share)."""
    d = legacy_design("rod1")
    s = compliance_sensitivity(d, ["materials.cfrp_tube.E_GPa", "materials.cfrp_tube.G_GPa"],
                               lambda x: calc_rod_compliance(x).C_F)
    elasticity_E = s.dC_F[0, 0, 0] * 100.0 / s.C_F[0, 0]
    assert -1.0 < elasticity_E < -0.8
    assert s.dC_F[1, 0, 0] == pytest.approx(0.0, abs=1e-12)                  # G does not bend the rod in plane
    assert s.dC_F[1, 1, 1] < 0                                                  # ... but twists pipe I


def test_method_accuracy_is_the_verification_data():
    """The stated bias and scatter of calc and frame are those of ln(method / solid) over the bent solid references."""
    from rodlab.fea.frame import frame_compliance
    from rodlab.fea.reference_designs import reference_design, solid_references
    from rodlab.core.sensitivity import STRUCTURAL_ENTRIES
    logs = {"calc": [], "frame": []}
    for name, ref in solid_references().items():
        try:
            d = reference_design(name)
        except (KeyError, RodlabError):
            continue
        Cs = np.array(ref["C_F"])
        if any(abs(Cs[m, n]) < 0.05 * np.sqrt(abs(Cs[m, m] * Cs[n, n])) for m, n in STRUCTURAL_ENTRIES):
            continue
        for method, C in (("calc", calc_rod_compliance(d).C_F), ("frame", frame_compliance(d)[0])):
            logs[method].append([np.log(C[m, n] / Cs[m, n]) for m, n in STRUCTURAL_ENTRIES])
    for method, rows in logs.items():
        r = np.array(rows)
        acc = METHOD_ACCURACY[method]
        assert len(r) >= 50
        assert np.allclose(r.mean(0), acc.bias, atol=2e-3) and np.allclose(r.std(0), acc.sd, rtol=0.05, atol=5e-4)
        assert np.allclose(np.corrcoef(r.T), acc.corr, atol=0.02)
    assert np.all(METHOD_ACCURACY["calc"].bias < 0)             # the closed form is stiffer than the solid


def test_edited_design_keeps_the_file_and_reads_back(tmp_path):
    src = _write(tmp_path)
    d = load_design(src)
    out = write_edited_design(src.read_text(), d, {"materials.cfrp_tube.E_GPa": 93.0, "bend.radius_mm": 55.0},
                              tmp_path / "asbuilt.rod.toml", "# as built\n")
    text = out.read_text()
    assert "# a comment that must survive" in text and "E_GPa = 93   # design: 100" in text
    back = load_design(out)
    assert design_value(back, "materials.cfrp_tube.E_GPa") == 93.0 and back.bend.radius_mm == 55.0
    # a built-in material the file does not define gets its own table with all its numbers
    d1 = resolve_design("rod1")
    t1 = edited_design_text(d1.source.read_text(), d1, {"materials.steel_304.E_GPa": 180.0})
    assert "[materials.steel_304]" in t1 and "density_kg_m3" in t1.split("[materials.steel_304]")[1]


def test_edited_design_refuses_an_invalid_result(tmp_path):
    src = _write(tmp_path)
    d = load_design(src)
    with pytest.raises(DesignError, match="nothing was written"):
        write_edited_design(src.read_text(), d, {"bend.radius_mm": 10.0}, tmp_path / "bad.rod.toml")
    assert not (tmp_path / "bad.rod.toml").exists()


def test_a_perturbed_design_is_the_file_update_writes(tmp_path):
    """A design read from a file is perturbed in that file's own tables, its defaults re-derived: the bend that is
    the tube itself moves with tube.* keys, a [pipe_I] override carries the bend and rings that follow it, a bend of
    its own keeps its section; the compliance of the perturbed design is that of the file update writes (a review:
    2-24 % apart in c33 where the defaults had been frozen)."""
    from rodlab.core.design_io import resolve_design
    from rodlab.fea.frame import frame_compliance
    head = 'format = "rodlab.rod/1"\nname = "al300"\nL1_mm = 300\nL2_mm = 450\ngamma_deg = 90.0\n'
    tube = '[tube]\nmaterial = "al_6061"\nouter_diameter_mm = 30\nwall_mm = 2.5\n'
    files = {"tube": head + tube, "pipe_I": head + tube + '[pipe_I]\nwall_mm = 2.8\n',
             "own bend": head + tube + '[bend]\nmaterial = "al_6061"\nouter_diameter_mm = 30\nwall_mm = 2.5\n'}
    for label, text in files.items():
        path = tmp_path / f"{label.replace(' ', '_')}.rod.toml"
        path.write_text(text)
        d = resolve_design(str(path))
        for key in ("tube.wall_mm", "tube.outer_diameter_mm", "pipe_I.wall_mm"):
            value = 0.9 * design_value(d, key)
            moved = with_values(d, {key: value})
            written = resolve_design(str(write_edited_design(text, d, {key: value}, tmp_path / "w.rod.toml", "")))
            assert np.allclose(frame_compliance(moved)[0], frame_compliance(written)[0], rtol=1e-12), (label, key)
    d = resolve_design(str(tmp_path / "tube.rod.toml"))
    assert with_values(d, {"tube.wall_mm": 2.3}).bend.wall_mm == 2.3
    assert with_values(resolve_design(str(tmp_path / "own_bend.rod.toml")), {"tube.wall_mm": 2.3}).bend.wall_mm == 2.5


def test_another_codes_fea_file_gets_no_bias_of_rodlabs_frame():
    """An fea file without rodlab's provenance.model (another code's FEA) is worth the solid's 1 % with no bias;
    rodlab's own frame and solid files keep theirs."""
    from rodlab.core.sensitivity import method_accuracy
    other = method_accuracy("fea", None)
    assert np.all(other.bias == 0) and np.allclose(other.sd, 0.01)
    assert np.all(method_accuracy("fea", "my-abaqus").bias == 0)
    assert method_accuracy("fea", "frame") is METHOD_ACCURACY["frame"]
    assert method_accuracy("fea", "solid") is METHOD_ACCURACY["solid"]
