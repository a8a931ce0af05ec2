"""The frame model against stored solid-FEA references (fea/data/solid_reference.json)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from rodlab.fea.frame import (FrameCalibration, bend_flexibility_factor, calibrate_frame, frame_errors, frame_segments,
                       shear_lag_mm)
from rodlab.core.enums import Part
from rodlab.core.layout import SegmentKind

from rodlab.fea.reference_designs import (family_errors, random_global_errors, random_references, reference_design,
                                          reference_sets, reference_spec, solid_references)

design = reference_design
_SETS = reference_sets()
CALIBRATION_SET, VALIDATION_SET, PROBE_SET, THIN_SET = (_SETS[k] for k in ("calibration", "validation", "probes",
                                                                           "thin"))
FAMILIES = _SETS["families"]
REFS = solid_references()


#: documented exceptions to the 2 % bound of the global default (docs/fea.md): hold-out L's sharp (115 deg),
#: thick-walled bend makes C_xz a near-cancelling sum (13 % change per 0.1 of the bend factor); blind Y's
#: 1 mm titanium wall (r_m / t = 9.5, h = 0.35) lies outside the calibrated range (bend r_m / t <= 7.9,
#: h >= 0.43) and is flagged
BOUNDS = {"L": 0.03, "Y": 0.03}


@pytest.mark.parametrize("name", CALIBRATION_SET + PROBE_SET + VALIDATION_SET)
def test_global_calibration_bounds(name):
    """Documented accuracy of the default frame model on every significant entry: the 18 calibration designs
    within 1.2 %, the 39 part probes within 1.9 %, the held-out and blind designs within 1.7 % (two documented
    exceptions)."""
    e = frame_errors(design(name), REFS[name]["C_F"], REFS[name]["C_g"])
    assert np.abs(e).max() < BOUNDS.get(name, 0.02), (name, np.abs(e).max())


def test_calibration_beats_plain_beam_theory():
    plain = FrameCalibration()
    worse = [np.sqrt(np.mean(frame_errors(design(n), REFS[n]["C_F"], REFS[n]["C_g"], plain) ** 2)) for n in REFS]
    better = [np.sqrt(np.mean(frame_errors(design(n), REFS[n]["C_F"], REFS[n]["C_g"]) ** 2)) for n in REFS]
    assert np.mean(better) < 0.2 * np.mean(worse)


def test_shear_lag_length_closed_form():
    """Two equal isotropic walls: lambda^2 = (3 G / 2 t) (2 / E t) -> 1 / lambda = t sqrt(E / 3 G)."""
    from rodlab import get_material
    st = get_material("steel_304")
    assert shear_lag_mm(st, 2.0, st, 2.0) == pytest.approx(2.0 * np.sqrt(st.E_GPa / 3 / st.G_axial_GPa), rel=1e-12)
    # torsion: G axial for the membrane, G23 through the thickness (= G for an isotropic wall)
    assert shear_lag_mm(st, 2.0, st, 2.0, torsion=True) == pytest.approx(2.0 / np.sqrt(3.0), rel=1e-12)
    # a soft-in-shear carbon wall transfers its load over a longer length than steel
    cf = get_material("cfrp")
    assert shear_lag_mm(cf, 2.0, st, 3.0) > 2 * shear_lag_mm(st, 2.0, st, 3.0)


def test_bend_flexibility_factor_limits():
    """ASME 1.65 / h for thin bends, von Karman's second approximation for thick ones, never below 1."""
    assert bend_flexibility_factor(0.02) == pytest.approx(82.5)
    assert bend_flexibility_factor(1.2) == pytest.approx(1.4927, abs=1e-4)   # ASME: 1.375
    hs = np.linspace(0.05, 5.0, 200)
    k = np.array([bend_flexibility_factor(h) for h in hs])
    assert np.all(np.diff(k) <= 1e-12) and k.min() >= 1.0


def test_sleeve_and_bend_zones_follow_the_parts():
    """Ineffective zones only at free ends: none at the clamp, none where ring 1 meets ring 2 on a straight rod
    (one continuous sleeve); the plug where it starts inside pipe II, the tube where pipe II ends on the stud;
    the bend's flexibility only between its restrained ends."""
    segs = frame_segments(design("D"))                    # straight, with rings
    ring = [s for s in segs if Part.RING_1 in s.parts or Part.RING_2 in s.parts]
    joint = [s for s in ring if s.slack]
    assert all(Part.RING_1 in s.slack or Part.RING_2 in s.slack for s in joint)
    ends = [s.s0_mm for s in joint]
    vertex = design("D").L1_mm
    assert all(abs(e - vertex) > 10.0 and abs(e + s.length_mm - vertex) > 10.0 for e, s in zip(ends, joint))
    assert not segs[0].slack                               # holder at the clamp: effective from the flange face
    plug = [s for s in segs if Part.BALL_HOLDER in s.parts and Part.PIPE_II in s.parts]
    assert plug[0].slack == (Part.BALL_HOLDER,) and plug[-1].slack == (Part.PIPE_II,)
    arcs = [s for s in frame_segments(design("rod1")) if s.kind is SegmentKind.ARC]
    assert len(arcs) == 3 and arcs[0].bend_flex == arcs[2].bend_flex == (1.0, 1.0) and arcs[1].bend_flex[0] > 1.5


def test_bend_ends_held_by_rings_saturate():
    """The arc's restrained ends grow with the hoop stiffness of ring + tube (none, a short or a 40 mm aluminium
    ring: the same hoop restraint; a steel ring 6 mm thick: longer) but stay below ``bend_end r_m`` (a ring far
    stiffer than the bend wall holds the end no rounder than a rigid one); a soft carbon tube with no ring
    hardly holds a steel bend at all."""
    from rodlab.fea.frame import CALIBRATION

    def end(name):
        return [s for s in frame_segments(design(name)) if s.kind is SegmentKind.ARC][0].length_mm
    none, short, al, steel = (end(n) for n in ("bend_steel_no_rings", "bend_steel_rings_20", "bend_steel_1.5_R40",
                                                "bend_steel_st34_40"))
    r_m = (22.0 - 1.5) / 2.0
    assert al == pytest.approx(short)
    assert 0 < none < al < steel < CALIBRATION.bend_end * r_m
    assert end("bend_cfrp_steel_no_rings") < 0.1 * none


def test_holder_zone_closed_form():
    """Pipe-holder zone = holder_end (E / E_t)^a (r_m / t)^b / lambda of the tube: longer for a thinner carbon
    wall, in shear-lag units too."""
    from rodlab.fea.frame import CALIBRATION as cal
    zones = {}
    for name in ("holder_cfrp_1.0_al37", "holder_cfrp_2.0_al37"):
        d = design(name)
        tube, holder = d.pipe_I, d.pipe_holder
        t2 = (holder.outer_diameter_mm - tube.outer_diameter_mm) / 2.0
        lam = shear_lag_mm(tube.material, tube.wall_mm, holder.material, t2)
        r_m = (tube.outer_diameter_mm - tube.wall_mm) / 2.0
        c = (cal.holder_end * (tube.material.E_GPa / tube.material.E_t_GPa) ** cal.holder_orthotropy
             * (r_m / tube.wall_mm) ** cal.holder_slenderness)
        segs = frame_segments(d)
        zone = sum(s.length_mm for s in segs if Part.PIPE_HOLDER in s.slack)
        assert zone == pytest.approx(min(c * lam, 0.45 * holder.length_mm), rel=1e-9)
        zones[name] = zone / lam
    assert zones["holder_cfrp_1.0_al37"] > 1.1 * zones["holder_cfrp_2.0_al37"]


@pytest.mark.parametrize("base", sorted(FAMILIES))
def test_family_calibration_transfers_over_L1_L2(base):
    """Calibrated on one solid run of the base design, the frame predicts the other L1 / L2 of the family
    (same sections; the paper's rods and an off-grid L1 / L2) within 1 % on every significant entry (steel
    4# -> 5#, 6#; carbon 1# -> 2#, 3#, whose short pipe I is almost all sleeve and bend: the shear-lag scaling
    of the sleeve ends carries over; and the thin titanium bend Y, outside the global calibration's range)."""
    cal = calibrate_frame([design(base)], [REFS[base]["C_F"]], [REFS[base]["C_g"]])
    for n in [base] + FAMILIES[base]:
        e = frame_errors(design(n), REFS[n]["C_F"], REFS[n]["C_g"], cal)
        assert np.abs(e).max() < 0.01, (n, np.abs(e).max())


@pytest.mark.slow
@pytest.mark.cad
def test_stored_reference_is_current():
    """The stored references (default solid model: half mesh, tube grading, ~0.11 % from converged) are
    today's default solid model: a change of mesh or solver defaults must refresh them
    (``python scripts/calibrate_frame.py --solve``) and refit the frame."""
    pytest.importorskip("gmsh")
    from rodlab.fea import solid_compliance
    from rodlab.geometry import mesh_rod
    comp, _ = solid_compliance(design("rod4"), mesh_rod,
                               error_estimate=False)
    ref = np.array(REFS["rod4"]["C_F"])
    big = np.abs(ref) > 1e-3 * np.abs(ref).max()
    np.testing.assert_allclose(comp.C_F[big], ref[big], rtol=1e-3)


def test_calibration_input_errors():
    with pytest.raises(ValueError, match="bend_scale_in must be a positive"):
        FrameCalibration(bend_scale_in=0.0)
    with pytest.raises(ValueError, match="sleeve_end must be a non-negative"):
        FrameCalibration(sleeve_end=float("nan"))
    assert FrameCalibration(holder_slenderness=-0.2).holder_slenderness == -0.2      # exponents take any sign
    with pytest.raises(ValueError, match="holder_orthotropy must be a finite"):
        FrameCalibration(holder_orthotropy=float("inf"))
    with pytest.raises(ValueError, match="Did you mean 'bend_scale_in'"):
        calibrate_frame([design("rod4")], [REFS["rod4"]["C_F"]], [REFS["rod4"]["C_g"]], names=("bend_scale_inn",))
    with pytest.raises(ValueError, match="one solid C_F and C_g per design"):
        calibrate_frame([design("rod4")], [], [])


def test_designs_outside_the_calibrated_range_are_flagged(tmp_path, capsys):
    """The designs the calibration was fitted on lie inside the calibrated range; thin-walled bends (blind Y,
    2.8 % off; the thin probes) do not, and the compliance file, the CLI and a sweep row say so."""
    import json as _json

    from rodlab.fea import compute_compliance
    from rodlab.fea.frame import frame_range_notes
    from rodlab.fea.sweep import run_sweep
    from conftest import write_toml
    from rodlab.app.cli import main
    for n in CALIBRATION_SET + PROBE_SET:
        assert frame_range_notes(design(n)) == [], n
    for n in THIN_SET:              # measured 1-4.4 % off (docs/fea.md): each one is flagged
        assert frame_range_notes(design(n)), n
    notes = frame_range_notes(design("Y"))
    assert len(notes) == 2 and "bend r_m / t = 9.50" in notes[0] and "bend h" in notes[1]
    assert compute_compliance(design("Y"), "frame").provenance["outside_calibrated_range"] == notes
    path = write_toml(tmp_path / "y.rod.toml", dict({"format": "rodlab.rod/1", "name": "Y"}, **reference_spec("Y")))
    out = tmp_path / "y.compliance.json"
    assert main(["fea", str(path), "--model", "frame", "-o", str(out)]) == 0
    assert "note: bend r_m / t = 9.50" in capsys.readouterr().out
    assert _json.loads(out.read_text())["provenance"]["outside_calibrated_range"] == notes
    df = run_sweep(design("Y"), [330.0], [400.0], use_dask=False, cache_dir=tmp_path / "cache")
    assert df["status"].tolist() == ["ok"] and "bend r_m / t" in df["message"][0]


def test_random_blind_designs_and_family_calibration():
    """60 random designs inside the calibrated range, none used for fitting (scripts/frame_random_blind.py,
    fea/data/solid_random_reference.json): the global default is typically within 0.7 % but up to 3.2 % off
    (docs/fea.md); joint-calibrated on one solid run of a family's base (``rodlab sweep --calibrate``, its
    stored section motions), both L1 / L2 variants of each of 10 of the worst families are within 0.4 %,
    where the global default is 1.4-5.2 % off."""
    refs = random_references()
    g = np.array(list(random_global_errors(refs).values()))
    assert g.size == 60
    assert np.median(g) < 0.008 and g.max() < 0.035
    fam = family_errors(refs)
    assert len(fam) == 10
    joints = np.array([e["joints"] for e in fam.values()])
    glob = np.array([e["global"] for e in fam.values()])
    assert joints.max() < 0.004
    assert glob.min() > 0.01 and glob.max() > 0.05          # what the joint calibration is needed for


@pytest.mark.parametrize("rod", ["rod1", "rod2"])
def test_the_builtin_carbon_rods_lie_inside_the_frames_range_and_within_1_percent(rod):
    """The built-in carbon rods (40 x 5 mm tubes, r_m / t 3.5) are inside the frame's stated range, and the frame
    is within 1 % of the solid FEA's largest entry on them (measured 0.3-0.8 %: the evidence the range was widened
    on). rod 2# is the shortest and worst."""
    from rodlab.core.design_io import resolve_design
    from rodlab.fea import compute_compliance
    from rodlab.fea.frame import frame_range_notes
    from rodlab.geometry import mesh_rod
    d = resolve_design(rod)
    assert frame_range_notes(d) == []
    solid, frame = compute_compliance(d, "solid", mesher=mesh_rod), compute_compliance(d, "frame")
    for a, b in ((frame.C_F, solid.C_F), (frame.C_g, solid.C_g)):
        assert np.abs(a - b).max() < 0.01 * np.abs(b).max()


CARBON_BEND = """format = "rodlab.rod/1"
name = "carbon-tol"
L1_mm = 350.0
L2_mm = 400.0
gamma_deg = 90.0
[tube]
material = "mycfrp"
outer_diameter_mm = 32.0
wall_mm = 3.0
[materials.mycfrp]
E_GPa = 120
E_transverse_GPa = 9
G_GPa = 5
nu = 0.3
density_kg_m3 = 1600
"""


def test_a_curved_carbon_bend_is_flagged_where_the_frame_is_far_off(tmp_path):
    """A new user's unidirectional-carbon rod whose bend is of the tube's carbon (no [bend] table): the frame's bend
    flexibility is calibrated on metal bends only, and here its c33 is ~40 % below the solid's; the frame's notes
    name the bend's material ratios (they said nothing before)."""
    from rodlab.core.design_io import resolve_design
    from rodlab.fea import compute_compliance
    from rodlab.geometry import mesh_rod
    path = tmp_path / "carbon-tol.rod.toml"
    path.write_text(CARBON_BEND)
    d = resolve_design(str(path))
    frame = compute_compliance(d, "frame")
    notes = frame.provenance["outside_calibrated_range"]
    assert any("bend material mycfrp: E / G over its isotropic value 2 (1 + nu) = 9.23" in n for n in notes)
    assert any("E / E_T = 13.33" in n for n in notes)
    solid = compute_compliance(d, "solid", mesher=mesh_rod, error_estimate=False)
    assert frame.C_F[2, 2] < 0.7 * solid.C_F[2, 2]              # what the note warns of
    from rodlab.core.materials import get_material
    from rodlab.fea.frame import frame_range_notes
    for name in ("alumina", "ti_6al4v", "al_6061", "zirconia"):   # isotropic bends of any nu are not flagged
        iso = replace(d, bend=replace(d.bend, material=get_material(name)))
        assert not [n for n in frame_range_notes(iso) if "bend material" in n], name
