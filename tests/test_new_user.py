"""What a new user tripped over (issue 46): a folder named like a built-in, a URDF broken by one typo, built-in
names where a file is expected, messages that name a temporary file, a flat rig recording, a study that drops a
design on the console."""
from __future__ import annotations

import logging
import re
from pathlib import Path

import pytest

from rodlab.app.cli.main import main
from rodlab.calibrate import CalibrationError, resolve_robot

ROOT = Path(__file__).resolve().parents[1]
UR5 = ROOT / "calibrate" / "robots" / "ur5.urdf"
DATA = ROOT / "benchmarks" / "data" / "jacobi2025"


# --- 1. a folder does not shadow a built-in name ---------------------------------------------------------------

def test_a_folder_named_like_a_builtin_robot_does_not_hide_it(tmp_path, monkeypatch, caplog):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ur5").mkdir()                         # what `--json ur5/cal.json` leaves behind
    (tmp_path / "TX90").mkdir()
    with caplog.at_level(logging.WARNING):
        assert resolve_robot("ur5").n == 6 and resolve_robot("TX90").n == 6
    assert "the built-in robot ur5, not the folder ur5/" in caplog.text
    (tmp_path / "arm").mkdir()
    with pytest.raises(CalibrationError, match="arm: this is a folder, not a robot file"):
        resolve_robot("arm")


def test_a_folder_named_like_a_builtin_design_does_not_hide_it(tmp_path, monkeypatch):
    from rodlab.core.design_io import resolve_design
    monkeypatch.chdir(tmp_path)
    (tmp_path / "rod1").mkdir()
    assert resolve_design("rod1").L1_mm == 300.0
    assert main(["info", "rod1"]) == 0


@pytest.fixture(scope="module")
def ur5_cal(tmp_path_factory) -> Path:
    """A UR5 calibration from every eighth grid pose, written where `--json ur5/cal.json` puts it."""
    lines = (DATA / "ur5_grid.validation.csv").read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")] + [next(ln for ln in lines if ln.startswith("q1"))]
    rows = [ln for ln in lines if ln and not ln.startswith(("#", "q1"))][::8]
    folder = tmp_path_factory.mktemp("user")
    points = folder / "fit.validation.csv"
    points.write_text("\n".join(head + rows) + "\n")
    assert main(["calibrate", "--points", str(points), "--robot", "ur5", "--fix-unidentifiable",
                 "--json", str(folder / "ur5" / "cal.json")]) in (0, 3)
    return folder / "ur5" / "cal.json"


def test_the_cli_takes_the_builtin_when_a_folder_has_its_name(ur5_cal, monkeypatch, capsys):
    monkeypatch.chdir(ur5_cal.parent.parent)           # ur5/ is a folder here
    points = str(ur5_cal.parent.parent / "fit.validation.csv")
    assert main(["calibrate", "--points", points, "--robot", "ur5", "--fix-unidentifiable"]) in (0, 3)
    assert "unknown robot file kind" not in capsys.readouterr().err
    assert main(["export", str(ur5_cal), "--robot", "ur5", "-o", "ur5/by_robot.urdf"]) == 0
    assert Path("ur5/by_robot.urdf").is_file()


# --- 4. export --urdf takes built-in names; the compliance it cannot hold is said first ---------------------------

def test_export_urdf_takes_a_builtin_name_and_warns_about_the_compliance_first(ur5_cal, tmp_path, capsys):
    capsys.readouterr()
    assert main(["export", str(ur5_cal), "--urdf", "ur5", "-o", str(tmp_path / "cal.urdf")]) == 0
    io = capsys.readouterr()
    assert (tmp_path / "cal.urdf").is_file() and "wrote" in io.out
    warning = next(ln for ln in io.err.splitlines() if ln.startswith("warning:"))
    assert "more than the model's own error" in warning and "--kinematic-only" in warning
    assert main(["export", str(ur5_cal), "--urdf", "tx90", "-o", str(tmp_path / "x.urdf")]) == 2
    assert "tx90.toml is not a URDF" in capsys.readouterr().err


# --- 2. a broken URDF is refused, naming the file, the joint or link and the line ---------------------------------

def _broken(tmp_path, name, old, new, count=1) -> Path:
    text = UR5.read_text()
    assert old in text
    path = tmp_path / f"{name}.urdf"
    path.write_text(text.replace(old, new, count))
    return path


def _line_of(path: Path, needle: str) -> int:
    return next(i for i, ln in enumerate(path.read_text().splitlines(), 1) if needle in ln)


def test_a_misspelled_child_link_is_refused_not_read_as_a_smaller_robot(tmp_path):
    path = _broken(tmp_path, "typo", '<child link="upper_arm_link"/>', '<child link="upper_arm_lnk"/>')
    with pytest.raises(CalibrationError) as e:
        resolve_robot(path)
    msg = str(e.value)
    assert f"line {_line_of(path, 'upper_arm_lnk')}" in msg and "shoulder_lift_joint" in msg
    assert "upper_arm_lnk" in msg and "Did you mean `upper_arm_link`" in msg and "typo.urdf" in msg


def test_a_missing_parent_link_is_refused(tmp_path):
    path = _broken(tmp_path, "parent", '<parent link="wrist_1_link"/>', '<parent link="wrist1_link"/>')
    with pytest.raises(CalibrationError, match=r"line \d+: joint 'wrist_2_joint': its parent link 'wrist1_link'"):
        resolve_robot(path)


def test_a_chain_cut_by_a_missing_joint_is_refused(tmp_path):
    text = UR5.read_text()
    cut = re.sub(r'<joint name="elbow_joint".*?</joint>', "", text, flags=re.S)
    path = tmp_path / "cut.urdf"
    path.write_text(cut)
    with pytest.raises(CalibrationError) as e:
        resolve_robot(path)
    msg = str(e.value)
    assert "'forearm_link' hangs from no joint" in msg and "stops before it" in msg
    line = _line_of(path, '<link name="forearm_link"')
    assert f"line {line}" in msg


@pytest.mark.parametrize("old, new, what", [
    ('<origin xyz="0 0 0.089159" rpy="0 0 0"/>', '<origin xyz="0 0.089159" rpy="0 0 0"/>', "shoulder_pan_joint"),
    ('<origin xyz="0 0 0.089159" rpy="0 0 0"/>', '<origin xyz="0 0 0.089159" rpy="0 0"/>', "shoulder_pan_joint"),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0 1"/>', "shoulder_pan_joint"),
    ('<axis xyz="0 0 1"/>', '<axis xyz="0 0 x"/>', "shoulder_pan_joint"),
])
def test_a_vector_without_three_numbers_is_refused_with_its_line(tmp_path, old, new, what):
    path = _broken(tmp_path, "short", old, new)
    with pytest.raises(CalibrationError) as e:
        resolve_robot(path)
    msg = str(e.value)
    assert f"line {_line_of(path, new)}" in msg and what in msg and "must hold 3 finite numbers" in msg


def test_a_tip_link_off_the_chain_is_refused(tmp_path):
    with pytest.raises(CalibrationError, match="does not hang from"):
        resolve_robot(UR5, base_link="forearm_link", tip_link="shoulder_link")


def test_the_cli_names_the_urdf_not_the_data(tmp_path, capsys):
    path = _broken(tmp_path, "typo", '<child link="upper_arm_link"/>', '<child link="upper_arm_lnk"/>')
    assert main(["calibrate", "--points", str(DATA / "ur5_random.validation.csv"), "--robot", str(path)]) == 2
    err = capsys.readouterr().err
    assert "typo.urdf, line" in err and "validation.csv" not in err


# --- 7. messages name the user's paths; built-in rods where a compliance file is taken ------------------------------

def test_an_output_that_is_a_folder_is_named_not_its_temporary_file(tmp_path, capsys):
    (tmp_path / "adir").mkdir()
    assert main(["compliance", "rod1", "-o", str(tmp_path / "adir")]) == 2
    err = capsys.readouterr().err
    assert f"{tmp_path / 'adir'}: this is a folder" in err and ".tmp" not in err
    assert list((tmp_path / "adir").iterdir()) == []


def test_rig_simulate_and_fit_take_a_builtin_design(tmp_path, capsys):
    rec = tmp_path / "rec.rig.csv"
    assert main(["rig", "simulate", "--sim", "rod1", "--noise-um", "0.2", "-o", str(rec)]) == 0
    assert main(["rig", "fit", str(rec), "--sim", "1#", "-o", str(tmp_path / "meas.compliance.json")]) == 0
    out = capsys.readouterr().out
    r_rod = float(re.search(r"r_rod \(Eq. 21\) = ([0-9.]+)", out).group(1))
    assert abs(r_rod - 1.0) < 0.01                     # the truth is the same closed-form compliance


# --- 6. a flat rig recording names the file and the cause ---------------------------------------------------------

def _flat_recording(src: Path, dst: Path, axis: str | None = None) -> Path:
    """``src`` with the gauges showing only noise (no load response) on every axis, or on ``axis`` only."""
    import numpy as np
    rng = np.random.default_rng(1)
    out = []
    for ln in src.read_text().splitlines():
        f = ln.split(",")
        if not ln.startswith(("#", "time_s")) and (axis is None or f[4] == axis):
            f[6:9] = [v if v == "" else f"{rng.normal(0, 0.0006):.4f}" for v in f[6:9]]
        out.append(",".join(f))
    dst.write_text("\n".join(out) + "\n")
    return dst


@pytest.mark.parametrize("axis", [None, "z"])
def test_a_flat_rig_recording_names_the_file_and_the_cause(tmp_path, capsys, axis):
    rec = tmp_path / "rec.rig.csv"
    assert main(["rig", "simulate", "--sim", "rod1", "-o", str(rec)]) == 0
    flat = _flat_recording(rec, tmp_path / "flat.rig.csv", axis)
    capsys.readouterr()
    for argv in (["rig", "fit", str(flat), "--sim", "rod1", "-o", str(tmp_path / "m.compliance.json")],
                 ["diagnose", "--rig", str(flat), "--sim", "rod1"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert f"{flat}" in err and f"no load response on axis {axis or ''}" in err, err
        assert "check the gauges" in err and "r_rod" not in err
    assert not (tmp_path / "m.compliance.json").exists()


# --- 5. a study prints every design it could not use, with the reason -----------------------------------------------

def test_study_prints_every_unusable_design_with_its_reason(tmp_path, capsys):
    # a 20 mm tube with an 11 mm wall is a rod, not a tube; a 50 mm variant of rod 1# takes its bend radius in
    # the base's ratio to the diameter (65 / 40), no longer 65 mm (below 1.5 diameters: had been invalid)
    assert main(["study", "rod1", "--tubes", "40x5,20x11,50x3", "--replicates", "1", "--methods", "calc",
                 "--no-calibrate", "--no-budget", "--serial", "-o", str(tmp_path / "study")]) == 0
    out = capsys.readouterr().out
    assert "1 of 3 designs not usable:" in out and "50x3: invalid" not in out
    line = next(ln for ln in out.splitlines() if "20x11: invalid" in ln)
    assert "wall 11.0 mm must be less than the outer radius 10.0 mm" in line


# --- 8. study figures: labels kept, one colour scale, the sweep's colour map; the help's "%%" -------------------------

def test_pareto_labels_of_designs_at_the_same_reach_do_not_cover_each_other():
    from rodlab.app.study.plots import pareto_labels
    xy = [(300.0, 200.0), (300.0, 204.0), (300.0, 204.0), (500.0, 100.0)]    # [pt]; two share a point
    labels = pareto_labels(xy, ["25x2", "28x2", "28x2b", "far"])
    texts = [t for _, t, _, _ in labels]
    assert sorted(texts) == ["25x2", "28x2, 28x2b", "far"]
    boxes = []
    for i, text, (dx, dy), ha in labels:
        w = 4.3 * len(text)
        x0 = xy[i][0] + dx - (w if ha == "right" else 0.0)
        boxes.append((x0, xy[i][1] + dy, x0 + w, xy[i][1] + dy + 9.0))
    for a in range(len(boxes)):
        for b in range(a):
            A, B = boxes[a], boxes[b]
            assert not (A[0] < B[2] and B[0] < A[2] and A[1] < B[3] and B[1] < A[3]), (labels[a], labels[b])


def test_study_heat_maps_share_one_scale_and_the_sweeps_colour_map(tmp_path, monkeypatch):
    import matplotlib
    matplotlib.use("Agg")
    import numpy as np
    import pandas as pd
    from matplotlib.axes import Axes

    from rodlab.app.study.plots import plot_heatmaps
    from rodlab.fea.sweep_plot import HEAT_CMAP
    calls = []
    real = Axes.pcolormesh

    def spy(self, *args, **kw):
        if kw.get("shading") == "nearest":                                    # the panels, not the colour bar
            calls.append(kw)
        return real(self, *args, **kw)
    monkeypatch.setattr(Axes, "pcolormesh", spy)
    L1, L2 = np.meshgrid([250.0, 300.0, 350.0], [400.0, 450.0])
    rows = []
    for m, level in (("none", 0.3), ("meas", 0.04)):
        for i, (a, b) in enumerate(zip(L1.ravel(), L2.ravel())):
            rows.append({"design": f"d{i}", "L1_mm": a, "L2_mm": b, "method": m, "mean_mm": level * (1 + 0.1 * i)})
    df = pd.DataFrame(rows)
    assert plot_heatmaps(df, tmp_path / "heat.png").stat().st_size > 10_000
    assert len(calls) == 2 and all(c["cmap"] == HEAT_CMAP for c in calls)
    norm = calls[0]["norm"]
    assert calls[1]["norm"] is norm                                            # one scale for every panel
    assert norm.vmin == pytest.approx(0.04) and norm.vmax == pytest.approx(0.3 * 1.5)


def test_study_help_has_no_doubled_percent(capsys):
    with pytest.raises(SystemExit):
        main(["study", "--help"])
    out = capsys.readouterr().out
    assert "90 % band" in out and "%%" not in out


# --- 8. a quiet local cluster; one --png convention ---------------------------------------------------------------

def test_sweep_starts_its_local_cluster_quietly(tmp_path):
    import subprocess
    import sys
    holder = None
    try:                                               # the dashboard's default port taken, as by another cluster
        import socket
        holder = socket.socket()
        holder.bind(("127.0.0.1", 8787))
        holder.listen()
    except OSError:
        holder = None
    try:
        run = subprocess.run([sys.executable, "-m", "rodlab", "sweep", "--L1", "250,300", "--L2", "400", "--workers",
                              "2", "-o", str(tmp_path / "sweep.csv")], capture_output=True, text=True, timeout=300)
    finally:
        if holder is not None:
            holder.close()
    assert run.returncode == 0, run.stderr
    assert "distributed" not in run.stderr and "8787" not in run.stderr and "dashboard" not in run.stderr, run.stderr
    assert (tmp_path / "sweep.png").is_file()


def test_png_is_a_folder_everywhere_and_a_file_for_one_figure(tmp_path, capsys):
    rec = tmp_path / "rec.rig.csv"
    assert main(["rig", "simulate", "--sim", "rod1", "-o", str(rec)]) == 0
    out = ["-o", str(tmp_path / "m.compliance.json")]
    assert main(["rig", "fit", str(rec), "--sim", "rod1", *out, "--png", str(tmp_path / "figs")]) == 0
    assert (tmp_path / "figs" / "fig8.png").is_file()                 # a folder: the figure under its name
    assert main(["rig", "fit", str(rec), "--sim", "rod1", *out, "--png", str(tmp_path / "mine.png")]) == 0
    assert (tmp_path / "mine.png").is_file()                          # one figure: FILE.png is the file
    assert main(["diagnose", "--rig", str(rec), "--sim", "rod1", "--png", str(tmp_path / "diag")]) == 0
    assert list((tmp_path / "diag").glob("*.png"))
    capsys.readouterr()
    with pytest.raises(SystemExit) as e:                               # several figures: a folder, never FILE.png
        main(["diagnose", "--rig", str(rec), "--sim", "rod1", "--png", str(tmp_path / "d.png")])
    assert e.value.code == 2 and "give a folder" in capsys.readouterr().err
    assert not (tmp_path / "d.png").exists()


def test_a_sweep_with_no_usable_design_fails_with_the_reasons(tmp_path, capsys):
    """L1 / L2 given in metres: every design is invalid; the sweep exits 2 naming the first reasons (a new-user
    trial's had exited 0 with an all-grey figure) before it runs or writes anything (another had found the table
    and figure written beside the error)."""
    out = tmp_path / "s.csv"
    assert main(["sweep", "--base", "rod1", "--L1", "0.3:0.5:0.1", "--L2", "0.4:0.6:0.1", "--serial", "-o",
                 str(out)]) == 2
    err = capsys.readouterr().err
    assert "none of the 9 designs of --L1 x --L2 is a valid rod" in err and "millimetr" in err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("entry,message", [
    ('"tube.outer_diameter_mm" = 50', "one standard deviation of 50 on a value of 40"),
    ('"materials.cfrp_tube.E_GPa" = "8 percent"', 'a percentage such as "5%"'),
])
def test_a_tolerance_no_part_has_is_refused_with_the_fix(tmp_path, capsys, entry, message):
    from rodlab.core.design_io import resolve_design
    text = Path(resolve_design("rod1").source).read_text()
    p = tmp_path / "t.rod.toml"
    p.write_text(text.rstrip("\n") + "\n\n[tolerances]\n" + entry + "\n")
    assert main(["validate", str(p)]) == 2
    assert message in capsys.readouterr().err


def test_pareto_labels_stay_inside_the_axes_and_leave_out_what_has_no_room():
    """A crowded front: labels never cover each other nor leave the axes' frame; those without room are left out."""
    from rodlab.app.study.plots import pareto_labels
    xy = [(100.0 + 3.0 * k, 50.0 + 1.0 * k) for k in range(12)]           # twelve points a few pt apart
    frame = (60.0, 40.0, 400.0, 300.0)
    labels = pareto_labels(xy, [f"1# {150 + 50 * k}-300" for k in range(12)], frame)
    assert 0 < len(labels) < 12
    boxes = []
    for i, text, (dx, dy), ha in labels:
        w = 4.3 * len(text)
        x0 = xy[i][0] + dx - (w if ha == "right" else 0.0)
        boxes.append((x0, xy[i][1] + dy, x0 + w, xy[i][1] + dy + 9.0))
    for a, A in enumerate(boxes):
        assert frame[0] <= A[0] and A[2] <= frame[2] and frame[1] <= A[1] and A[3] <= frame[3], labels[a]
        for B in boxes[:a]:
            assert not (A[0] < B[2] and B[0] < A[2] and A[1] < B[3] and B[1] < A[3])
