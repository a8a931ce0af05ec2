"""Robots from URDF, DH and modified-DH descriptions, converted exactly; calibrated URDF / YAML / CSV exports."""
from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from rodlab.calibrate import ModelParams, builtin_robots, read_robot, resolve_robot
from rodlab.calibrate.errors import CalibrationError
from rodlab.calibrate.kinematics import forward
from rodlab.core.frames import pose_to_matrix

yourdfpy = pytest.importorskip("yourdfpy")


def _rpy_matrix(r, p, y):
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def _random_urdf(rng, n=6, parallel=(1,), fixed_between=(3,), tilt_rad=0.0, flange_rpy="0.2 -0.4 0.7") -> str:
    """A URDF with rotated joint frames, skew axes, a parallel pair (joint k+1 || k+2, or ``tilt_rad`` apart), a
    fixed link with mass in the chain and a lateral tool0 offset: nothing lines up with DH on purpose."""
    links = ['<link name="base_link"/>']
    joints = []
    parent = "base_link"
    axes = [rng.normal(size=3) for _ in range(n)]
    for i in range(n):
        child = f"link_{i + 1}"
        xyz = rng.uniform(-0.4, 0.4, 3)
        rpy = rng.uniform(-1.0, 1.0, 3) if i - 1 not in parallel else np.zeros(3)
        if i - 1 in parallel:
            axes[i] = axes[i - 1].copy()              # same axis in the (unrotated) child frame: parallel axes
            if tilt_rad:
                w = np.cross(axes[i], rng.normal(size=3))
                axes[i] = axes[i] / np.linalg.norm(axes[i]) + math.tan(tilt_rad) * w / np.linalg.norm(w)
        ax = axes[i] / np.linalg.norm(axes[i])
        m, c = rng.uniform(1, 30), rng.uniform(-0.2, 0.2, 3)
        links.append(f'<link name="{child}"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}" rpy="0 0 0"/>'
                     f'<mass value="{m}"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>')
        joints.append(f'<joint name="j{i + 1}" type="revolute"><origin xyz="{xyz[0]} {xyz[1]} {xyz[2]}" '
                      f'rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/><parent link="{parent}"/><child link="{child}"/>'
                      f'<axis xyz="{ax[0]} {ax[1]} {ax[2]}"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')
        parent = child
        if i in fixed_between:
            links.append(f'<link name="spacer_{i + 1}"><inertial><origin xyz="0.1 0 0" rpy="0 0 0"/><mass value="4"/>'
                         '<inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>')
            joints.append(f'<joint name="fix{i + 1}" type="fixed"><origin xyz="0.05 0.02 0.1" rpy="0.3 0.1 -0.2"/>'
                          f'<parent link="{parent}"/><child link="spacer_{i + 1}"/></joint>')
            parent = f"spacer_{i + 1}"
    links.append('<link name="tool0"/>')
    joints.append(f'<joint name="flange" type="fixed"><origin xyz="0.03 -0.02 0.12" rpy="{flange_rpy}"/>'
                  f'<parent link="{parent}"/><child link="tool0"/></joint>')
    return '<?xml version="1.0"?>\n<robot name="skew">' + "".join(links + joints) + "</robot>\n"


def _tip_in_base(robot, q):
    fr = forward(ModelParams.nominal(robot, np.zeros(3)), q)
    return robot.base_T_0 @ fr.T[:, -1] @ robot.n_T_tip


def _yourdfpy_fk(path, q, frame_to, frame_from):
    m = yourdfpy.URDF.load(str(path), load_meshes=False)
    out = []
    for qq in q:
        m.update_cfg(qq)
        out.append(m.get_transform(frame_to, frame_from))
    T = np.array(out)
    T[:, :3, 3] *= 1000.0
    return T


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_urdf_model_has_the_urdf_forward_kinematics(tmp_path, seed):
    """The converted model's tip frame equals the parser's own forward kinematics to 1e-6 mm (and rotation)."""
    rng = np.random.default_rng(seed)
    path = tmp_path / "skew.urdf"
    path.write_text(_random_urdf(rng))
    robot = read_robot(path)
    q = rng.uniform(-3, 3, (25, 6))
    ours, theirs = _tip_in_base(robot, q), _yourdfpy_fk(path, q, "tool0", "base_link")
    assert np.abs(ours[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-6
    assert np.abs(ours[:, :3, :3] - theirs[:, :3, :3]).max() < 1e-9
    assert 1 in robot.parallel_rows()                  # joints 2 and 3 parallel: Hayati's beta on row 2
    assert robot.joint_names == tuple(f"j{i}" for i in range(1, 7))


@pytest.mark.parametrize("tilt_deg", [2e-4, 0.5])
def test_nearly_parallel_axes_get_a_hayati_row(tmp_path, tilt_deg):
    """Axes 2e-4 deg apart (a rounded rpy in a real URDF) or 0.5 deg apart: a Hayati row (d = 0, the tilt in
    alpha and beta), not a common normal kilometres away. The conversion stays exact and the row is one where
    beta is identified."""
    rng = np.random.default_rng(7)
    path = tmp_path / "tilted.urdf"
    path.write_text(_random_urdf(rng, tilt_rad=math.radians(tilt_deg)))
    robot = read_robot(path)
    q = rng.uniform(-3, 3, (25, 6))
    ours, theirs = _tip_in_base(robot, q), _yourdfpy_fk(path, q, "tool0", "base_link")
    assert np.abs(ours[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-6
    assert np.abs(ours[:, :3, :3] - theirs[:, :3, :3]).max() < 1e-9
    assert robot.parallel_rows() == [1] and robot.d_mm[1] == 0.0
    tilt = np.degrees(np.arccos(np.cos(np.radians(robot.alpha_deg[1])) * np.cos(np.radians(robot.beta_deg[1]))))
    assert tilt == pytest.approx(tilt_deg, rel=1e-3)
    assert np.abs(robot.d_mm).max() < 1500 and np.abs(robot.a_mm).max() < 1500   # no far-away normal


def test_urdf_masses_are_lumped_onto_the_joint_that_moves_them(tmp_path):
    """Total mass and the first moment of every moving link (fixed spacer folded in) are kept."""
    rng = np.random.default_rng(5)
    path = tmp_path / "skew.urdf"
    path.write_text(_random_urdf(rng))
    robot = read_robot(path)
    m = yourdfpy.URDF.load(str(path), load_meshes=False)
    total = sum(lk.inertial.mass for lk in m.robot.links if lk.inertial is not None)
    assert robot.mass_kg.sum() == pytest.approx(total)
    # first moment at q = 0 in the base link, from the parser's frames
    moment = np.zeros(3)
    for lk in m.robot.links:
        if lk.inertial is not None:
            T = m.get_transform(lk.name, "base_link")
            moment += lk.inertial.mass * (T[:3, :3] @ lk.inertial.origin[:3, 3] + T[:3, 3]) * 1000.0
    fr = forward(ModelParams.nominal(robot, np.zeros(3)), np.zeros((1, 6)))
    ours = sum(robot.mass_kg[i] * (robot.base_T_0 @ fr.T[0, i + 1] @ np.r_[robot.com_mm[i], 1.0])[:3]
               for i in range(6))
    assert np.allclose(ours, moment, atol=1e-6)


def test_builtin_fanuc_urdf_matches_its_data_sheet_rows():
    """The built-in URDF (ROS-Industrial layout) is the data-sheet model: DH rows 670/312/1075/225/1280/215."""
    robot = resolve_robot("r2000ic165f")
    assert str(robot.path).endswith(".urdf") and "tool0" in robot.source
    assert np.allclose(np.abs(robot.d_mm), [670, 0, 0, 1280, 0, 215], atol=1e-9)
    assert np.allclose(robot.a_mm, [312, 1075, 225, 0, 0, 0], atol=1e-9)
    assert robot.parallel_rows() == [1]
    assert np.allclose(robot.n_T_tip, np.eye(4), atol=1e-12)      # {6} is tool0
    q = np.random.default_rng(3).uniform(-2, 2, (20, 6))
    theirs = _yourdfpy_fk(robot.path, q, "tool0", "base_link")
    assert np.abs(_tip_in_base(robot, q)[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-6


#: Universal Robots' published DH (d, a) [mm] of the UR10 and the UR5
_UR_DH = {"ur10": ([127.3, 0, 0, 163.941, 115.7, 92.2], [0, -612.0, -572.3, 0, 0, 0]),
          "ur5": ([89.159, 0, 0, 109.15, 94.65, 82.3], [0, -425.0, -392.25, 0, 0, 0])}


def _ur_dh_fk(q, model="ur10"):
    """Universal Robots' published DH (standard convention) in UR's "base" frame, written out independently."""
    d, a = _UR_DH[model]
    alpha = [math.pi / 2, 0, 0, math.pi / 2, -math.pi / 2, 0]
    out = []
    for qq in q:
        T = np.eye(4)
        for th, di, ai, al in zip(qq, d, a, alpha):
            ct, st, ca, sa = math.cos(th), math.sin(th), math.cos(al), math.sin(al)
            T = T @ np.array([[ct, -st * ca, st * sa, ai * ct], [st, ct * ca, -ct * sa, ai * st], [0, sa, ca, di],
                              [0, 0, 0, 1]])
        out.append(T)
    return np.array(out)


@pytest.mark.parametrize("model, mass_kg", [("ur10", 7.1 + 12.7 + 4.27 + 2.0 + 2.0 + 0.365),
                                             ("ur5", 3.7 + 8.393 + 2.275 + 1.219 + 1.219 + 0.1879)])
def test_builtin_ur_urdfs_are_universal_robots_dh_models(model, mass_kg):
    """The built-in UR10 and UR5 URDFs (ur_description layout) have UR's DH kinematics: tool0 in the 'base' frame
    equals the DH flange frame, J2 / J3 / J4 parallel (Hayati rows 2 and 3)."""
    robot = resolve_robot(model)
    q = np.random.default_rng(4).uniform(-3, 3, (25, 6))
    base_in_base_link = _yourdfpy_fk(robot.path, q[:1], "base", "base_link")[0]
    ours = np.linalg.inv(base_in_base_link) @ _tip_in_base(robot, q)
    theirs = _ur_dh_fk(q, model)
    assert np.abs(ours[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-6
    assert np.abs(ours[:, :3, :3] - theirs[:, :3, :3]).max() < 1e-9
    assert robot.parallel_rows() == [1, 2]
    assert robot.mass_kg.sum() == pytest.approx(mass_kg)


def _mdh_fk(rows, q, flange):
    """Craig's modified DH, written out independently: T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i)."""
    out = []
    for qq in q:
        T = np.eye(4)
        for (al, a, th, d), qi in zip(rows, qq):
            A = pose_to_matrix([a, 0, 0, al, 0, 0]) @ pose_to_matrix([0, 0, d, 0, 0, math.degrees(qi) + th])
            T = T @ A
        out.append(T @ flange)
    return np.array(out)


_PUMA = [(0, 0, 0, 0), (-90, 0, 0, 243.5), (0, 431.8, 0, -93.4), (90, -20.3, 0, 433.1), (-90, 0, 0, 0),
         (90, 0, 0, 0)]


def _puma_file(path, flange, header=()):
    """A PUMA-560-like modified-DH table (Craig, Table 3.4) with ``flange_pose = flange``."""
    text = ['format = "rodlab.robot/2"', 'convention = "mdh"', *header, f"flange_pose = {flange}"]
    for al, a, th, d in _PUMA:
        text += ["[[joint]]", f"alpha_deg = {al}", f"a_mm = {a}", f"theta_offset_deg = {th}", f"d_mm = {d}"]
    path.write_text("\n".join(text) + "\n")
    return path


def test_modified_dh_table_is_converted_exactly(tmp_path):
    """A PUMA-560-like modified-DH table (Craig): the model's flange frame equals the table's."""
    flange = [0, 0, 56.25, 0, 0, 0]
    robot = read_robot(_puma_file(tmp_path / "puma.toml", flange, ['name = "puma"', 'source = "Craig, Table 3.4"']))
    q = np.random.default_rng(0).uniform(-3, 3, (30, 6))
    theirs = _mdh_fk(_PUMA, q, pose_to_matrix(flange))
    ours = _tip_in_base(robot, q)
    assert np.abs(ours[:, :3, 3] - theirs[:, :3, 3]).max() < 1e-6
    assert np.abs(ours[:, :3, :3] - theirs[:, :3, :3]).max() < 1e-9
    assert robot.source == "Craig, Table 3.4" and robot.parallel_rows() == [1]


@pytest.mark.parametrize("flange", [[0, 0, 56.25, 1e-3, 2e-3, 30], [0, 0, 56.25, 12, -7, 30]])
def test_a_flange_tilted_off_the_last_axis_still_ends_the_model_on_the_flange(tmp_path, flange):
    """A flange tilted off the last axis, by 1e-3 deg (a rounded or calibrated description) or by 12 deg: {n} is
    the flange frame exactly (was: a common normal far away, d_n of metres)."""
    robot = read_robot(_puma_file(tmp_path / "tilted_flange.toml", flange))
    q = np.random.default_rng(3).uniform(-3, 3, (30, 6))
    assert np.abs(_tip_in_base(robot, q) - _mdh_fk(_PUMA, q, pose_to_matrix(flange))).max() < 1e-6
    assert np.abs(robot.n_T_tip - np.eye(4)).max() < 1e-8 and robot.d_mm[-1] == pytest.approx(56.25)


def _dh_fk(tx90, q, flange):
    out = []
    for qq in q:
        T = np.eye(4)
        for th, d, a, al, qi in zip(tx90.theta_offset_deg, tx90.d_mm, tx90.a_mm, tx90.alpha_deg, qq):
            T = T @ pose_to_matrix([0, 0, d, 0, 0, th + math.degrees(qi)]) @ pose_to_matrix([a, 0, 0, al, 0, 0])
        out.append(T @ flange)
    return np.array(out)


@pytest.mark.parametrize("flange", [[0, 0, 100, 0, 0, 90], [0, 0, 100, 10, 5, 30], [0, 0, 80, 180, 0, 0],
                                    [5, -3, 100, 10, 0, 90], [5, 0, 100, 0, 1.5, 0]])
def test_a_dh_flange_pose_is_folded_into_the_last_row(tmp_path, flange):
    """A classic-DH file with a flange_pose: {n} becomes the flange frame (tool vectors and a rod's matrices are
    given there), rows 1..n-1 stay as written, the kinematics are exact; a flange off the last axis keeps its
    offset in n_T_tip."""
    tx90 = resolve_robot("tx90")
    text = ['format = "rodlab.robot/2"', f"flange_pose = {flange}"]
    for th, d, a, al in zip(tx90.theta_offset_deg, tx90.d_mm, tx90.a_mm, tx90.alpha_deg):
        text += ["[[joint]]", f"theta_offset_deg = {th}", f"d_mm = {d}", f"a_mm = {a}", f"alpha_deg = {al}"]
    path = tmp_path / "tx90_flange.toml"
    path.write_text("\n".join(text) + "\n")
    robot = read_robot(path)
    q = np.random.default_rng(4).uniform(-3, 3, (30, 6))
    assert np.abs(_tip_in_base(robot, q) - _dh_fk(tx90, q, pose_to_matrix(flange))).max() < 1e-6
    assert np.array_equal(robot.d_mm[:-1], tx90.d_mm[:-1]) and np.array_equal(robot.a_mm[:-1], tx90.a_mm[:-1])
    if flange[:2] == [0, 0]:                            # on the last axis, tilted or not: {n} is the flange
        assert np.abs(robot.n_T_tip - np.eye(4)).max() < 1e-9
        assert robot.d_mm[-1] == pytest.approx(tx90.d_mm[-1] + flange[2])
    else:                                               # off the axis: its origin and z, a turn about z left
        assert np.abs(robot.n_T_tip[:3, 3]).max() < 1e-9
        assert np.abs(robot.n_T_tip[:3, 2] - [0, 0, 1]).max() < 1e-9


def test_dh_rows_are_read_as_written_and_convert_to_themselves():
    """Classic DH (the TX90 of the paper) needs no conversion; its axes rebuild the same kinematics."""
    from rodlab.calibrate.robot import dh_zero_chain, robot_from_chain
    tx90 = resolve_robot("tx90")
    assert tx90.d_mm[0] == 150.0 and tx90.source.startswith("Wan et al.")
    again = robot_from_chain(dh_zero_chain(tx90))
    q = np.random.default_rng(1).uniform(-3, 3, (30, 6))
    assert np.abs(_tip_in_base(tx90, q) - _tip_in_base(again, q)).max() < 1e-9
    assert again.parallel_rows() == tx90.parallel_rows() == [1]


def test_robot_file_errors_name_the_problem(tmp_path):
    bad = tmp_path / "bad.urdf"
    bad.write_text('<?xml version="1.0"?>\n<robot name="x">\n  <link name="a">\n</robot>\n')
    with pytest.raises(CalibrationError, match=r"bad.urdf, line \d+: not valid XML"):
        read_robot(bad)
    xacro = tmp_path / "arm.urdf"
    xacro.write_text('<robot xmlns:xacro="http://wiki.ros.org/xacro"><xacro:macro name="m"/></robot>')
    with pytest.raises(CalibrationError, match="xacro file: expand it first"):
        read_robot(xacro)
    urdf = tmp_path / "skew.urdf"
    urdf.write_text(_random_urdf(np.random.default_rng(0)))
    with pytest.raises(CalibrationError, match="no link named 'tool1'.*tool0"):
        read_robot(urdf, tip_link="tool1")
    with pytest.raises(CalibrationError, match="choose a chain in a URDF"):
        resolve_robot("tx90", base_link="base_link")
    slide = tmp_path / "slide.urdf"
    slide.write_text(_random_urdf(np.random.default_rng(0)).replace('name="j3" type="revolute"',
                                                                     'name="j3" type="prismatic"'))
    with pytest.raises(CalibrationError, match="j3.*prismatic"):
        read_robot(slide)
    sniffed = tmp_path / "arm.xml"                      # an existing URDF is not "not valid TOML"
    sniffed.write_text(urdf.read_text())
    assert read_robot(sniffed).n == 6


def _calibration_file(tmp_path, robot, rng):
    """A result file of a perturbed model (what `rodlab calibrate --json` writes)."""
    from rodlab.calibrate.params import catalogue, structural_fixed
    from rodlab.core.fileio import atomic_write_json
    fixed = structural_fixed(robot, np.array([10.0, 0.0, 150.0]))
    nominal = {"d": robot.d_mm, "a": robot.a_mm, "alpha": robot.alpha_deg, "beta": robot.beta_deg}
    params = {}
    for info in catalogue(robot.n):
        if info.name in fixed:
            v = float(nominal[info.kind][info.index]) if info.kind in nominal else 0.0
        elif info.kind in nominal:
            v = float(nominal[info.kind][info.index]) + rng.normal(scale=0.3)
        elif info.kind == "c":
            v = abs(rng.normal(scale=1e-6))
        else:
            v = rng.normal(scale=200.0 if info.unit == "mm" else 5.0)
        params[info.name] = {"value": v, "sigma": 0.01, "unit": info.unit,
                             "status": "fixed" if info.name in fixed else "identified"}
    path = tmp_path / "cal.json"
    atomic_write_json(path, {"format": "rodlab.calibration/1", "robot": robot.name, "compensation": "none",
                             "trusted": True, "parameters": params, "residual_rms_mm": 0.01})
    return path


def test_export_writes_a_urdf_with_the_calibrated_kinematics(tmp_path):
    """`rodlab export --urdf`: the written URDF, read by the parser, puts rodlab_tcp where the calibrated model
    puts the tool point (<= 1 um); the YAML and the DH CSV carry the values and sigmas."""
    import yaml

    from rodlab.calibrate.result import calibrated_params, read_calibration
    from rodlab.app.cli.main import main
    urdf = tmp_path / "skew.urdf"
    urdf.write_text(_random_urdf(np.random.default_rng(7)))
    robot = read_robot(urdf)
    cal_path = _calibration_file(tmp_path, robot, np.random.default_rng(8))
    assert main(["export", str(cal_path), "--urdf", str(urdf), "-o", str(tmp_path / "out" / "cal.urdf")]) == 0
    params = calibrated_params(robot, read_calibration(cal_path))
    q = np.random.default_rng(9).uniform(-3, 3, (20, 6))
    theirs = _yourdfpy_fk(tmp_path / "out" / "cal.urdf", q, "rodlab_tcp", "rodlab_measurement")
    model = forward(params.with_(c=np.zeros(6)), q).pW
    assert np.abs(theirs[:, :3, 3] - model).max() < 1e-3
    nominal = forward(ModelParams.nominal(robot, params.tool, params.base), q).pW
    assert np.abs(nominal - model).max() > 1.0        # the check above is not trivially true
    text = (tmp_path / "out" / "cal.urdf").read_text()
    assert "Joint compliance cannot be expressed in URDF" in text
    data = yaml.safe_load((tmp_path / "out" / "cal.yaml").read_text())
    assert set(data["kinematics"]) == set(robot.joint_names)
    assert data["joint_compliance"]["j2"]["value"] == pytest.approx(params.c[1])
    assert data["parameters"]["a_3"]["sigma"] == 0.01
    with open(tmp_path / "out" / "cal.dh.csv") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    assert [r["name"] for r in rows] == list(robot.joint_names)
    assert float(rows[2]["a_calibrated"]) == pytest.approx(params.a[2])
    assert float(rows[2]["a_nominal"]) == pytest.approx(robot.a_mm[2])


def test_export_refuses_a_result_of_another_robot_description(tmp_path, capsys):
    from rodlab.app.cli.main import main
    cal_path = _calibration_file(tmp_path, resolve_robot("tx90"), np.random.default_rng(0))
    assert main(["export", str(cal_path), "--urdf", str(builtin_robots()["r2000ic165f"]), "-o",
                 str(tmp_path / "x.urdf")]) == 2
    assert "another description of the robot" in capsys.readouterr().err
    assert not (tmp_path / "x.urdf").exists()


def test_the_documented_minimal_robot_file_reads(tmp_path):
    """docs/formats.md's minimal robot file is a valid robot (the docs cannot drift from the reader)."""
    from pathlib import Path
    text = (Path(__file__).resolve().parents[1] / "docs" / "formats.md").read_text()
    section = text.split("## Robot file", 1)[1]
    block = section.split("```toml\n", 1)[1].split("```", 1)[0]
    path = tmp_path / "two.toml"
    path.write_text(block)
    robot = read_robot(path)
    assert robot.n == 2 and robot.source == "my sketch"
