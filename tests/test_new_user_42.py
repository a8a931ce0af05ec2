"""What a new-user trial (2026-11-29, lab technician and calibration engineer) found, fixed: a load cell in kgf read
as N (a compliance 9.8x too large, written without a word), a failed acquisition's header-only file, the simulator's
Modbus port refusing a second client with a traceback, campaign rows in radians among rows in degrees, a typo in a
probe file's header key, a device file of another device, a flagged fixture missing from NOT TRUSTED, a load cell
that saw no load."""
from __future__ import annotations

import argparse
import types
from pathlib import Path

import numpy as np
import pytest

from rodlab.app.cli.deviceargs import flagged_fixture_reasons
from rodlab.app.cli.main import main
from rodlab.calibrate.readings import point_unit_slips, unit_slips
from rodlab.stiffness_rig import DeviceError, fit_recording, read_recording
from rodlab.stiffness_rig import instruments
from rodlab.stiffness_rig.instrument_profile import Instrument
from rodlab.stiffness_rig.recording import RecordingWriter

termios = pytest.importorskip("termios")


# ---------------------------------------------------------------- the load cell's unit

def _with_force(tmp_path, factor: float = 1.0, name: str = "r.rig.csv") -> Path:
    """A simulated recording of rod1 with a load cell, its force_N column times ``factor``."""
    src = tmp_path / "src.rig.csv"
    if not src.exists():
        assert main(["rig", "simulate", "--sim", "rod1", "--effect", "friction:F_f_N=0.5", "--load-cell-noise-n",
                     "0.01", "--seed", "3", "-o", str(src)]) == 0
    out, head = [], None
    for ln in src.read_text().splitlines():
        if ln.startswith("#") or head is None and not ln.startswith("#"):
            if not ln.startswith("#"):
                head = ln.split(",")
            out.append(ln)
            continue
        cells = ln.split(",")
        k = head.index("force_N")
        if cells[k]:
            cells[k] = f"{float(cells[k]) * factor:.5f}"
        out.append(",".join(cells))
    path = tmp_path / name
    path.write_text("\n".join(out) + "\n")
    return path


def test_a_load_cell_in_kgf_is_refused_and_named(tmp_path, capsys):
    rec = _with_force(tmp_path, 1 / 9.80665, "kgf.rig.csv")
    out = tmp_path / "m.compliance.json"
    assert main(["rig", "fit", str(rec), "--sim", "rod1", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert "grows 0.10" in err and "look like kgf" in err and "--load mass" in err and not out.exists()
    # on the hung masses the file is right: the same c22 as the load cell in N gives
    assert main(["rig", "fit", str(rec), "--sim", "rod1", "-o", str(out), "--load", "mass"]) == 0
    good = fit_recording(read_recording(_with_force(tmp_path)))
    import json
    c22 = json.loads(out.read_text())["C_F_mm_per_N"][1][1]
    assert c22 == pytest.approx(good.C_F_meas[1, 1], rel=0.02)


def test_a_calibrated_load_cell_passes_and_a_few_per_cent_is_warned(tmp_path):
    good = fit_recording(read_recording(_with_force(tmp_path)))
    assert good.success and all(sc.ratio == pytest.approx(1.0, abs=0.01) for sc in good.load.scale)
    assert not [w for w in good.warnings if "grows" in w]
    off = fit_recording(read_recording(_with_force(tmp_path, 1.05, "off.rig.csv")))
    assert off.success and any("calibration factor is +5.0 % off" in w for w in off.warnings)


def test_a_load_cell_that_saw_no_load_is_named(tmp_path, capsys):
    src = _with_force(tmp_path)
    lines, head = [], None
    for ln in src.read_text().splitlines():
        if ln.startswith("#") or head is None:
            head = head if ln.startswith("#") else ln.split(",")
            lines.append(ln)
            continue
        cells = ln.split(",")
        if cells[head.index("load_axis")] == "z" and cells[head.index("force_N")]:
            cells[head.index("force_N")] = "0.00010"
        lines.append(",".join(cells))
    rec = tmp_path / "noz.rig.csv"
    rec.write_text("\n".join(lines) + "\n")
    assert main(["rig", "fit", str(rec), "--sim", "rod1", "-o", str(tmp_path / "x.json")]) == 2
    assert "it saw no load along z" in capsys.readouterr().err.replace("\n", " ")


# ---------------------------------------------------------------- the instruments' ports and the recording

def test_a_port_refusing_its_settings_is_a_device_error(monkeypatch):
    def refuse(*a, **k):
        raise termios.error(22, "Invalid argument")
    monkeypatch.setattr(instruments.serial, "serial_for_url", refuse)
    ins = Instrument("dial_y", "/dev/ttyUSB9", "digimatic", {"request": "1\\r"}, (), 19200, 8, "E", 1.0, 0.2, 3)
    with pytest.raises(DeviceError) as e:
        instruments.InstrumentClient(ins)
    assert "parity E" in str(e.value) and "parity = \"N\"" in str(e.value) and e.value.key == "instrument.parity"


def test_a_writer_that_recorded_nothing_leaves_no_file(tmp_path):
    w = RecordingWriter(tmp_path / "r.rig.csv", {"rod": "1#"})
    assert (tmp_path / "r.rig.csv").exists() and w.discard_if_empty() and not (tmp_path / "r.rig.csv").exists()
    w = RecordingWriter(tmp_path / "s.rig.csv", {"rod": "1#"})
    w.write(0.0, 0, 0, "load", "y", 0.0, (0.0, 0.0, 0.0), 20.0)
    assert not w.discard_if_empty() and (tmp_path / "s.rig.csv").exists()
    before = (tmp_path / "s.rig.csv").read_bytes()
    again = RecordingWriter(tmp_path / "s.rig.csv", {"rod": "1#"})       # a resume: kept whatever happens
    assert not again.discard_if_empty() and (tmp_path / "s.rig.csv").read_bytes() == before


def test_the_served_profile_has_no_parity(tmp_path):
    """The example profile's load cell speaks Modbus with parity E; a pty has none (Linux drops PARENB and glibc
    refuses the settings: the trial's second acquisition stopped with a traceback)."""
    from rodlab.app.cli.rig_served import profile_simulators
    from rodlab.stiffness_rig.model import RigModel
    src = Path(__file__).resolve().parents[1] / "stiffness_rig" / "plans" / "two-digimatic-loadcell.profile.toml"
    args = argparse.Namespace(profile=str(src), link_dir=str(tmp_path / "rig"))
    sims, _ = profile_simulators(args, RigModel(np.eye(3) * 1e-3), None)
    for s in sims:
        s.stop()
    served = (tmp_path / "rig" / "sim.profile.toml").read_text()
    assert 'parity = "E"' in src.read_text() and 'parity = "E"' not in served and 'parity = "N"' in served


# ---------------------------------------------------------------- campaigns, probes, fixtures

def _campaign(q_deg):
    n = len(q_deg)
    return types.SimpleNamespace(q_deg=np.asarray(q_deg, float), lines=np.arange(2, n + 2), x_D_mm=np.full((n, 3), 0.1))


def test_rows_in_radians_among_degrees_are_named():
    rng = np.random.default_rng(4)
    q = rng.uniform(-150, 150, (12, 6))
    q[4] = np.radians(q[4])
    q[7:9] = np.radians(q[7:9])
    slips = unit_slips(_campaign(q), "c.campaign.csv")
    assert len(slips) == 1 and "3 row(s) (line 6, 9, 10)" in slips[0] and "180/pi" in slips[0]
    near_zero = q.copy()
    near_zero[4] = [0.5, -1.0, 0.2, 0.0, 0.1, 0.0]          # within a degree of the zero on all but one joint
    near_zero[7:9] = rng.uniform(-150, 150, (2, 6))
    assert unit_slips(_campaign(near_zero), "c.campaign.csv") == []
    pts = types.SimpleNamespace(q_deg=q, x_W_mm=np.full((12, 3), 900.0))
    assert "data row 5, 8, 9" in point_unit_slips(pts, "p.validation.csv")[0]


def test_a_typo_in_the_probe_files_accuracy_key_is_named(tmp_path):
    path = tmp_path / "p.probe.csv"
    path.write_text("# acuracy_mm: 0.005\nposition,feature,x_mm,y_mm,z_mm\n1,ball_1,0,0,0\n")
    from rodlab.calibrate import CalibrationError, read_probe
    with pytest.raises(CalibrationError) as e:
        read_probe(path)
    assert "Did you mean `accuracy_mm`" in str(e.value) and e.value.key == "acuracy_mm"


def test_a_flagged_fixture_is_the_first_reason_not_to_trust():
    fix = types.SimpleNamespace(probing={"flagged": {"1": "ball_2 350.4643 mm off"}})
    (reason,) = flagged_fixture_reasons(fix, "f.fixture.json")
    assert "position 1: ball_2 350.4643 mm off" in reason and "probe them again" in reason
    assert flagged_fixture_reasons(types.SimpleNamespace(probing=None), "f.fixture.json") == []


def test_points_far_by_one_offset_name_the_device_files_zero():
    from rodlab.app.cli.deviceargs import _common_offset
    rng = np.random.default_rng(2)
    shifted = np.array([2.5, 2.4, 2.45]) + rng.normal(0, 0.1, (30, 3))
    said = _common_offset(shifted, argparse.Namespace(device="s.device.json"))
    assert "one offset (+2.4" in said and "s.device.json has another zero (zero_mm)" in said
    assert _common_offset(rng.normal(0, 3.0, (30, 3)), argparse.Namespace(device=None)) == ""   # scattered


def test_a_joint_compliance_at_its_bound_is_marked():
    from rodlab.app.cli.calibration_printers import _at_bound
    from rodlab.calibrate.estimate import C_MAX
    assert _at_bound(6.5e-17, 3.8e-6) == " (at its bound)" and _at_bound(C_MAX, 1e-6) == " (at its bound)"
    assert _at_bound(3.0e-6, 3.8e-6) == ""


def test_an_acquisition_that_fails_before_its_first_sample_leaves_no_file(tmp_path):
    """The trial's wrong-protocol instrument answered nothing for 23 s and left a header-only recording."""
    from rodlab.stiffness_rig.acquire import acquire
    from rodlab.stiffness_rig.config import Channel, RigPlan, RigProfile
    from rodlab.stiffness_rig.model import LoadSchedule

    class Silent:                                  # an instrument that never answers usably
        garbage = reconnects = 0

        def command_loader(self, *a):
            pass

        def read_sample(self):
            raise DeviceError("instrument 'controller' answers nothing usable")

        read = read_sample

    prof = RigProfile(port="/dev/null", protocol="query", channels=tuple(Channel(i, i, 1.0, 0.001) for i in range(3)),
                      loader_command="LOAD {axis} {phase} {mass_kg:.4f}\r\n")
    plan = RigPlan("1#", LoadSchedule(axes=("y",), masses=(1.0,), repeats=1, hold_s=0.5, rate_Hz=20.0),
                   settle_window_s=0.25, settle_tolerance_mm=0.004, settle_timeout_s=1.0)
    out = tmp_path / "r.rig.csv"
    with pytest.raises(DeviceError):
        acquire(prof, plan, out, use_loader=True, client=Silent())
    assert not out.exists()


def test_a_load_cell_wired_the_other_way_is_named_not_the_gauges(tmp_path, capsys):
    rec = _with_force(tmp_path, -1.0, "neg.rig.csv")
    assert main(["rig", "fit", str(rec), "--sim", "rod1", "-o", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err.replace("\n", " ")
    assert "opposite sign" in err and "gauge reads the rod's motion backwards" not in err


def test_diagnose_refuses_a_load_cell_in_another_unit(tmp_path, capsys):
    rec = _with_force(tmp_path, 1 / 4.4482216, "lbf.rig.csv")
    assert main(["diagnose", "--rig", str(rec), "--sim", "rod1"]) == 2
    err = capsys.readouterr().err.replace("\n", " ")
    assert "look like lbf" in err and "--units-checked" in err


def test_fit_on_the_masses_keeps_what_the_load_cell_said(tmp_path, capsys):
    import json
    rec = _with_force(tmp_path, 1 / 9.80665, "kgf.rig.csv")
    out = tmp_path / "m.json"
    assert main(["rig", "fit", str(rec), "--sim", "rod1", "-o", str(out), "--load", "mass"]) == 0
    left = json.loads(out.read_text())["provenance"]["load_cell_left_out"]
    assert left["scale"] and all(abs(s["ratio"] - 0.102) < 0.002 for s in left["scale"])
    assert "look like kgf" in left["problems"][0] and "look like kgf" in capsys.readouterr().err


def test_every_position_flagged_names_the_device_file_or_the_accuracy():
    from rodlab.app.cli.cmd_fixture import _all_flagged
    pos = lambda j, name: types.SimpleNamespace(position=j, suspect=(name, 7.8), swapped=None)   # noqa: E731
    same = types.SimpleNamespace(flagged=[pos(j, "ball_3") for j in (1, 2, 3)], accuracy_mm=0.005)
    said = _all_flagged(same, "other.device.json")
    assert "same suspect feature 'ball_3'" in said and "other.device.json does not describe" in said
    mixed = types.SimpleNamespace(flagged=[pos(1, "ball_1"), pos(2, "pin")], accuracy_mm=0.001)
    said = _all_flagged(mixed, "d.device.json")
    assert said.index("accuracy_mm (0.001 mm)") < said.index("d.device.json")


def test_the_units_the_load_scale_check_names_are_units_a_profile_takes(tmp_path):
    """The check's advice (units = "gf") must be a setting the profile reader and its schema accept."""
    from rodlab.app.cli.cmd_validate import validate_file
    from rodlab.stiffness_rig.config import read_profile
    from rodlab.stiffness_rig.instrument_profile import UNITS
    src = Path(__file__).resolve().parents[1] / "stiffness_rig" / "plans" / "two-digimatic-loadcell.profile.toml"
    text = src.read_text()
    assert 'units = "N"' in text
    for unit in UNITS["force"]:
        mine = tmp_path / f"{unit}.profile.toml"
        mine.write_text(text.replace('units = "N"', f'units = "{unit}"'))
        assert read_profile(mine) and validate_file(mine).ok, unit


def test_pardiso_solves_a_single_right_hand_side():
    import scipy.sparse as sp
    from rodlab.fea.solver import PatternSolver, available_backend
    if available_backend() != "pardiso":
        pytest.skip("PARDISO is not available here")
    A = sp.diags([[-1.0] * 9, [4.0] * 10, [-1.0] * 9], [-1, 0, 1], format="csc")
    b = np.arange(10.0)
    x = PatternSolver(A, "pardiso").factor(A)(b)
    assert x.shape == (10,) and np.allclose(A @ x, b)


def test_validate_and_calibrate_name_joint_readings_beyond_the_robots_limits(tmp_path, capsys):
    """`validate` took no robot (the trial: campaigns of other robots could only be checked in part); a campaign
    of another robot beyond the TX90's limits is named row by row, a 5-column file against a 6-axis robot refused."""
    from rodlab.calibrate import resolve_robot
    from rodlab.calibrate.readings import limit_breaches
    tx90 = resolve_robot("tx90")
    q = np.zeros((4, 6))
    q[2, 1] = tx90.limits_deg[1, 0] - 5.0                       # q2 5 deg below its lower limit
    (said,) = limit_breaches(q, np.arange(2, 6), tx90, "c.campaign.csv")
    assert "1 row(s)" in said and f"line 4 q2 = {q[2, 1]:.2f}" in said and "joint(s) 2" in said
    assert limit_breaches(np.zeros((4, 6)), None, tx90, "p.csv") == []
    camp = tmp_path / "c.campaign.csv"
    rows = ["position,point,q1,q2,q3,q4,q5,q6,x_mm,y_mm,z_mm"]
    rows += [f"1,{k},10,{-140 if k == 2 else -40},90,0,45,0,0.1,0.0,0.0" for k in range(1, 4)]
    camp.write_text("\n".join(rows) + "\n")
    assert main(["validate", str(camp), "--robot", "tx90"]) == 0
    out = capsys.readouterr().out
    assert "1 warning(s)" in out and "line 3 q2 = -140.00" in out
    five = tmp_path / "five.campaign.csv"
    five.write_text("\n".join(r.rsplit(",q6", 1)[0] + ",x_mm,y_mm,z_mm" if i == 0 else
                              ",".join(r.split(",")[:7] + r.split(",")[8:]) for i, r in enumerate(rows)) + "\n")
    assert main(["validate", str(five), "--robot", "tx90"]) == 2
    assert "q6" in capsys.readouterr().err


def test_mesh_refuses_a_size_that_would_never_finish_and_another_format(tmp_path, capsys):
    """The designer trial's `--size 0.01` ran for ten minutes without a word; `-o x.vtk` got gmsh's format."""
    assert main(["mesh", "rod1", "-o", str(tmp_path / "r.msh"), "--size", "0.01"]) == 2
    err = capsys.readouterr().err
    assert "tetrahedra" in err and "give --size" in err and not (tmp_path / "r.msh").exists()
    assert main(["mesh", "rod1", "-o", str(tmp_path / "r.vtk")]) == 2
    assert "ending in .msh" in capsys.readouterr().err and not (tmp_path / "r.vtk").exists()


def test_update_names_the_closed_form_a_simulated_recording_came_from(tmp_path, capsys):
    """rig simulate --sim DESIGN is the closed form; update fits through the frame: on a shear-soft carbon rod with
    a titanium bend (c33 21 % apart) the unchanged design was refused with no word of why."""
    design = tmp_path / "t1.rod.toml"
    design.write_text('format = "rodlab.rod/1"\nname = "T1"\nL1_mm = 350.0\nL2_mm = 700.0\ngamma_deg = 90.0\n'
                      '[tube]\nmaterial = "my_cf"\nouter_diameter_mm = 36.0\nwall_mm = 3.0\n'
                      '[bend]\nmaterial = "ti_6al4v"\nwall_mm = 3.0\nradius_mm = 72.0\n'
                      '[materials.my_cf]\nE_GPa = 135.0\nE_transverse_GPa = 8.0\nG_GPa = 5.0\nnu = 0.3\n'
                      'density_kg_m3 = 1580\n[tolerances]\n"materials.my_cf.E_GPa" = "10%"\n'
                      '"materials.my_cf.G_GPa" = "25%"\n')
    rec = tmp_path / "self.rig.csv"
    assert main(["-q", "rig", "simulate", "--sim", str(design), "-o", str(rec)]) == 0
    capsys.readouterr()
    assert main(["update", str(design), "--measured", str(rec), "-o", str(tmp_path / "t1.asbuilt.rod.toml")]) == 3
    err = capsys.readouterr().err.replace("\n", " ")
    assert "the design's closed form, which differs from the frame model by" in err and "c33" in err
    assert f"with --sim {design} (calc)" in err                   # the header names what was simulated
    text = rec.read_text().replace(f"# sim: {design} (calc)", "# sim: mine.compliance.json (fea, frame)")
    other = tmp_path / "other.rig.csv"                             # another model's truth: no closed form to blame
    other.write_text(text)
    main(["update", str(design), "--measured", str(other), "-o", str(tmp_path / "t2.asbuilt.rod.toml")])
    assert "closed form, which differs" not in capsys.readouterr().err


def test_a_study_tells_a_designer_what_an_unidentifiable_campaign_means():
    from rodlab.app.study.prepare import study_reason
    from rodlab.calibrate import CalibrationError
    e = CalibrationError("this campaign cannot identify 2 parameter(s): dtheta_6 has no effect on the measured "
                         "points; c_6 has no effect on the measured points. Add clamping positions or rod orientations "
                         "(more varied joint angles), or hold them with --pin NAME=VALUE (without --strict rodlab "
                         "holds them at nominal itself)")
    said = study_reason(e)
    assert "--pin" not in said and "--strict" not in said and "dtheta_6 has no effect" in said
    assert "gamma below 180" in said and "--orientations" in said
    assert study_reason(CalibrationError("something else")) == "prediction: something else"


def test_tolerance_problems_name_their_own_lines(tmp_path, capsys):
    """Quoted dotted keys ("tube.wall_mm" = ...) were located at their table's header line."""
    design = tmp_path / "t.rod.toml"
    design.write_text('format = "rodlab.rod/1"\nname = "T"\nL1_mm = 300.0\nL2_mm = 450.0\ngamma_deg = 90.0\n'
                      '[tube]\nmaterial = "cfrp"\nouter_diameter_mm = 40.0\nwall_mm = 5.0\n[tolerances]\n'
                      '"tube.outer_diameter" = 0.1\n"tube.wall_mm" = "ten%"\n"materials.cfrp.E_GPa" = -5\n')
    assert main(["validate", str(design)]) == 2
    err = capsys.readouterr().err
    assert "line 11, key `tolerances.\"tube.outer_diameter\"`" in err
    assert "line 12, key `tolerances.tube.wall_mm`" in err and "line 13, key `tolerances.materials" in err


def test_a_common_material_name_and_lengths_in_metres_are_named_first():
    from rodlab.core.errors import DesignError
    from rodlab.core.materials import get_material
    with pytest.raises(DesignError, match="Did you mean `cfrp`"):
        get_material("carbon")
    import tomllib
    from rodlab.core.design_io import design_from_dict
    text = ('format = "rodlab.rod/1"\nname = "M"\nL1_mm = 0.3\nL2_mm = 0.6\ngamma_deg = 90.0\n[tube]\n'
            'material = "cfrp"\nouter_diameter_mm = 30.0\nwall_mm = 2.0\n')
    with pytest.raises(DesignError) as e:
        design_from_dict(tomllib.loads(text), text=text)
    assert str(e.value).index("did you give metres (0.3 m = 300 mm, 0.6 m = 600 mm)") < str(e.value).index("too short")


def test_a_bend_angle_in_radians_is_said_beside_an_unknown_material():
    """`validate` lists every problem at once: a part's problem (material "carbon") had hidden gamma_deg = 1.5708."""
    import tomllib
    from rodlab.core.design_io import design_from_dict
    from rodlab.core.errors import DesignError
    text = ('format = "rodlab.rod/1"\nname = "R"\nL1_mm = 300.0\nL2_mm = 450.0\ngamma_deg = 1.5708\n[tube]\n'
            'material = "carbon"\nouter_diameter_mm = 30.0\nwall_mm = 2.0\n')
    with pytest.raises(DesignError) as e:
        design_from_dict(tomllib.loads(text), text=text)
    assert e.value.key == "tube.material" and [a.key for a in e.value.also] == ["gamma_deg"]
    assert "looks like radians" in str(e.value.also[0]) and e.value.also[0].line == 5
