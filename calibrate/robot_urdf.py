"""URDF robots: the serial chain from ``base_link`` to ``tip_link``, read with yourdfpy and made exact DH rows.

A URDF (``.urdf``; xacro must be expanded first: ``xacro robot.urdf.xacro > robot.urdf``) is a tree of links
joined by joints whose ``origin`` places the joint frame in the parent link and whose ``axis`` (in the joint
frame) the child turns about. The chain from the base link (default: the tree's root) to the tip link
(default: ``tool0`` when present, else the only leaf behind the most revolute joints) gives the joint axes at
q = 0; fixed joints are folded in, the links' ``<inertial>`` masses are lumped onto the joint that moves them.
:func:`calibrate.robot_lines.dh_rows` then makes the calibrator's rows (parallel axes get Hayati's beta).
"""
from __future__ import annotations

import contextlib
import logging
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rodlab.core.errors import did_you_mean

from .errors import CalibrationError
from .robot import Robot, robot_from_chain
from .robot_lines import ZeroChain
from .robot_reader import RobotFormat
from .urdf_check import check_urdf_structure

__all__ = ["read_urdf", "load_urdf", "quiet_mesh_names", "UrdfChain", "urdf_chain", "chain_poses", "zero_chain", "ROBOT_FORMAT"]

log = logging.getLogger(__name__)
_MOVING = ("revolute", "continuous")


@dataclass(frozen=True)
class UrdfChain:
    """The links and joints between two links of a URDF, with every link's pose at q = 0.

    model : the yourdfpy ``URDF``; base_link, tip_link : the chain's ends; joints : the chain's joints from
    base to tip (fixed ones included); revolute : names of the moving joints, in order;
    link_T : link name -> shape=(4, 4) pose in the base link at q = 0 [mm] (every link of the tree that hangs
    from the base); owner : link name -> index of the revolute joint that moves it (-1: none)
    """

    model: object
    base_link: str
    tip_link: str
    joints: tuple
    revolute: tuple
    link_T: dict
    owner: dict


def load_urdf(path):
    """The parsed file (yourdfpy, meshes not loaded); errors name the file and line."""
    p = Path(path)
    if not p.is_file():
        raise CalibrationError("file not found", path=p)
    text = p.read_text(encoding="utf-8", errors="replace")
    try:
        root = ET.fromstring(text)
    except ET.ParseError as e:
        raise CalibrationError(f"not valid XML: {e}", path=p, line=e.position[0]) from e
    if root.tag != "robot":
        raise CalibrationError(f"expected a <robot> root element (URDF), got <{root.tag}>", path=p)
    if "${" in text or any("xacro" in str(k) for k in root.attrib) or "xacro:" in text:
        raise CalibrationError("this is a xacro file: expand it first (`xacro robot.urdf.xacro > robot.urdf`, "
                               "`pip install xacro` outside ROS)", path=p)
    check_urdf_structure(text, p)
    import yourdfpy                                      # heavy (trimesh): only for URDF robots
    try:
        with quiet_mesh_names():
            return yourdfpy.URDF.load(str(p), build_scene_graph=False, load_meshes=False,
                                      load_collision_meshes=False)
    except Exception as e:  # noqa: BLE001 - the parser's own errors carry no common base
        raise CalibrationError(f"the URDF parser refused the file: {e}", path=p) from e


@contextlib.contextmanager
def quiet_mesh_names():
    """yourdfpy resolves the mesh file names of a URDF it reads or writes, meshes unused: a URDF copied away from its
    package logs one warning per mesh (11 for a Panda). Its warnings are held back meanwhile; errors pass."""
    log = logging.getLogger("yourdfpy")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(level)


def _pose(joint, q: float = 0.0) -> np.ndarray:
    """The joint's child link in its parent link [mm] at joint value q [rad]."""
    T = np.array(joint.origin if joint.origin is not None else np.eye(4), float)
    T[:3, 3] *= 1000.0
    if joint.type in _MOVING and q != 0.0:
        from scipy.spatial.transform import Rotation                    # heavy (scipy.spatial, ~0.35 s)
        axis = np.asarray(joint.axis if joint.axis is not None else (1.0, 0.0, 0.0), float)
        R = np.eye(4)
        R[:3, :3] = Rotation.from_rotvec(axis / np.linalg.norm(axis) * q).as_matrix()
        T = T @ R
    return T


def _tree(model):
    by_child = {j.child: j for j in model.robot.joints}
    children = {}
    for j in model.robot.joints:
        children.setdefault(j.parent, []).append(j)
    return by_child, children


def _default_tip(base: str, children: dict, path=None) -> str:
    leaves, stack = [], [(base, 0)]
    while stack:
        link, moving = stack.pop()
        kids = children.get(link, [])
        if not kids:
            leaves.append((moving, link))
        stack += [(j.child, moving + (j.type in _MOVING)) for j in kids]
    names = [name for _, name in leaves]
    if "tool0" in names:
        return "tool0"
    best = max(m for m, _ in leaves)
    top = [name for m, name in leaves if m == best]
    if len(top) > 1:
        raise CalibrationError(f"several tip links behind {best} moving joints: {sorted(top)}; choose one with "
                               "--tip-link", path=path, key="tip_link")
    return top[0]


def urdf_chain(model, base_link: str | None = None, tip_link: str | None = None, path=None) -> UrdfChain:
    """The chain from ``base_link`` to ``tip_link`` (defaults: the root; ``tool0`` or the deepest leaf)."""
    by_child, children = _tree(model)
    links = [lk.name for lk in model.robot.links]
    roots = [lk for lk in links if lk not in by_child]
    base = base_link or (roots[0] if roots else None)
    for what, name in (("base_link", base), ("tip_link", tip_link)):
        if name is not None and name not in links:
            raise CalibrationError(f"no link named {name!r}." + did_you_mean(str(name), links), path=path, key=what)
    tip = tip_link or _default_tip(base, children, path)
    joints, link = [], tip
    while link != base:
        if link not in by_child:
            raise CalibrationError(f"{tip!r} does not hang from {base!r}; choose --base-link / --tip-link on one "
                                   "branch", path=path, key="tip_link")
        joints.append(by_child[link])
        link = by_child[link].parent
    joints.reverse()
    _check_joints(joints, path)
    revolute = tuple(j.name for j in joints if j.type in _MOVING)
    link_T, owner = _zero_poses(base, children, revolute)
    return UrdfChain(model, base, tip, tuple(joints), revolute, link_T, owner)


def _check_joints(joints, path) -> None:
    for j in joints:
        if j.type not in _MOVING + ("fixed",):
            raise CalibrationError(f"joint {j.name!r} is {j.type}: the calibrator models serial chains of revolute "
                                   "joints (fixed joints are folded in)", path=path, key=j.name)
        if j.mimic is not None:
            raise CalibrationError(f"joint {j.name!r} mimics {j.mimic.joint!r}: coupled joints are not modelled",
                                   path=path, key=j.name)


def _zero_poses(base: str, children: dict, revolute: tuple) -> tuple[dict, dict]:
    """Every link below the base at q = 0, and which chain joint moves it (joints off the chain held at 0)."""
    link_T, owner, stack = {base: np.eye(4)}, {base: -1}, [base]
    while stack:
        link = stack.pop()
        for j in children.get(link, []):
            link_T[j.child] = link_T[link] @ _pose(j)
            owner[j.child] = revolute.index(j.name) if j.name in revolute else owner[link]
            stack.append(j.child)
    return link_T, owner


def _lumped_masses(model, ch: UrdfChain) -> tuple[np.ndarray, np.ndarray]:
    n = len(ch.revolute)
    mass, moment = np.zeros(n), np.zeros((n, 3))
    for lk in model.robot.links:
        k = ch.owner.get(lk.name, -1)
        if k < 0 or lk.inertial is None or not lk.inertial.mass:
            continue
        T = ch.link_T[lk.name]
        o = np.zeros(3) if lk.inertial.origin is None else np.asarray(lk.inertial.origin, float)[:3, 3] * 1000.0
        mass[k] += lk.inertial.mass
        moment[k] += lk.inertial.mass * (T[:3, :3] @ o + T[:3, 3])
    com = np.divide(moment, mass[:, None], out=np.zeros_like(moment), where=mass[:, None] > 0)
    return mass, com


def _limits(joints) -> np.ndarray:
    out = []
    for j in joints:
        lim = j.limit
        if j.type == "continuous" or lim is None or lim.lower is None or lim.upper is None or lim.lower >= lim.upper:
            out.append([-180.0, 180.0])
        else:
            out.append(np.rad2deg([lim.lower, lim.upper]))
    return np.array(out, float)


def zero_chain(ch: UrdfChain, name: str, source: str) -> ZeroChain:
    """The chain's axes at q = 0 in the base link (for :func:`calibrate.robot_lines.dh_rows`)."""
    moving = [j for j in ch.joints if j.type in _MOVING]
    points, dirs = [], []
    for j in moving:
        T = ch.link_T[j.child]
        axis = np.asarray(j.axis if j.axis is not None else (1.0, 0.0, 0.0), float)
        points.append(T[:3, 3])
        dirs.append(T[:3, :3] @ (axis / np.linalg.norm(axis)))
    mass, com = _lumped_masses(ch.model, ch)
    if not mass.any():
        log.warning("%s: no <inertial> masses on the chain: the links' weight adds no joint torque (only the rod "
                    "or payload loads the joint compliance)", source)
    return ZeroChain(name, np.array(points), np.array(dirs), ch.link_T[ch.tip_link], _limits(moving), mass, com,
                     np.array([0.0, 0.0, -9.80665]), source)


def read_urdf(path, base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """The calibrator's robot of a URDF's chain (exact: same forward kinematics to round-off)."""
    p = Path(path)
    model = load_urdf(p)
    ch = urdf_chain(model, base_link, tip_link, path=p)
    if len(ch.revolute) < 2:
        raise CalibrationError(f"{len(ch.revolute)} revolute joint(s) between {ch.base_link!r} and {ch.tip_link!r}; "
                               "the calibrator needs a serial arm (check --base-link / --tip-link)", path=p)
    name = model.robot.name or p.stem
    source = f"{p.name} ({ch.base_link} -> {ch.tip_link})"
    return robot_from_chain(zero_chain(ch, name, source), ch.revolute, path=p)


def chain_poses(ch: UrdfChain, q_rad) -> np.ndarray:
    """The tip link in the base link for configurations ``q_rad`` shape=(N, n) [rad] -> (N, 4, 4) [mm]."""
    q = np.atleast_2d(np.asarray(q_rad, float))
    T = np.broadcast_to(np.eye(4), (q.shape[0], 4, 4)).copy()
    k = 0
    for j in ch.joints:
        if j.type in _MOVING:
            T = T @ np.array([_pose(j, qq) for qq in q[:, k]])
            k += 1
        else:
            T = T @ _pose(j)
    return T


#: URDF files in the registry (:data:`rodlab.calibrate.robot_formats.ROBOT_READERS`)
ROBOT_FORMAT = RobotFormat(read_urdf, "a URDF (xacro expanded)", "urdf", suffix=".urdf")
