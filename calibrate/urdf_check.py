"""A URDF's structure checked before it becomes a robot, with the line of every fault.

The URDF parser takes a joint whose child link is misspelled, or a joint that is missing, as a smaller tree
and the chain then stops early: a 6-axis arm read as a 2-axis one without a word. So, before parsing: every
joint names a parent and a child link the file has, every link but one (the root) is the child of exactly one
joint, and every ``origin xyz/rpy`` and ``axis xyz`` holds three finite numbers. Errors name the file, the
joint or link, and the line.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from rodlab.core.errors import did_you_mean

from .errors import CalibrationError

__all__ = ["check_urdf_structure"]

#: element -> its attributes that hold a 3-vector
_VECTORS = {"origin": ("xyz", "rpy"), "axis": ("xyz",)}


@dataclass
class _Node:
    """One XML element: tag, attributes, the line of its start tag, its children."""

    tag: str
    attrs: dict
    line: int
    children: list = field(default_factory=list)

    def child(self, tag: str):
        return next((c for c in self.children if c.tag == tag), None)


def _parse(text: str) -> _Node:
    """The element tree with line numbers (the XML is known to be well formed)."""
    parser = expat.ParserCreate()
    root = _Node("", {}, 0)
    stack = [root]

    def start(tag, attrs):
        node = _Node(tag, attrs, parser.CurrentLineNumber)
        stack[-1].children.append(node)
        stack.append(node)

    parser.StartElementHandler = start
    parser.EndElementHandler = lambda tag: stack.pop()
    parser.Parse(text, True)
    return root.children[0]


def _check_vectors(node: _Node, path, owner: str) -> None:
    for attr in _VECTORS.get(node.tag, ()):
        if attr not in node.attrs:
            continue
        words = node.attrs[attr].split()
        try:
            ok = len(words) == 3 and all(math.isfinite(float(w)) for w in words)
        except ValueError:
            ok = False
        if not ok:
            raise CalibrationError(f"{owner}: <{node.tag} {attr}=\"{node.attrs[attr]}\"> must hold 3 finite numbers "
                                   f"(x y z), got {len(words)} value(s)", path=path, line=node.line)
    for c in node.children:
        _check_vectors(c, path, owner)


def _links(robot: _Node, path) -> dict[str, int]:
    links: dict[str, int] = {}
    for node in robot.children:
        if node.tag != "link":
            continue
        name = node.attrs.get("name")
        if not name:
            raise CalibrationError("a <link> without a name", path=path, line=node.line)
        if name in links:
            raise CalibrationError(f"link {name!r} is defined twice (first on line {links[name]})", path=path,
                                   line=node.line)
        links[name] = node.line
        _check_vectors(node, path, f"link {name!r}")
    return links


def _joint_link(joint: _Node, role: str, links: dict, path) -> str:
    name = joint.attrs.get("name", "?")
    el = joint.child(role)
    if el is None or not el.attrs.get("link"):
        raise CalibrationError(f"joint {name!r} has no <{role} link=\"...\"/>", path=path, line=joint.line)
    link = el.attrs["link"]
    if link not in links:
        raise CalibrationError(f"joint {name!r}: its {role} link {link!r} is not a link of this file (no <link "
                               f"name=\"{link}\">), so the chain would break there." + did_you_mean(link, links),
                               path=path, line=el.line)
    return link


def _check_tree(links: dict, edges: list, path) -> None:
    """Every link but the root hangs from a joint: a second root means a joint is missing or misnamed."""
    children = {child for _, child in edges}
    roots = [name for name in links if name not in children]        # file order: the root comes first
    if len(roots) > 1:
        first, cut = roots[0], roots[1:]
        them = "it" if len(cut) == 1 else "them"
        raise CalibrationError(
            f"the links do not form one tree: {', '.join(repr(c) for c in cut)} hang{'s' if len(cut) == 1 else ''} "
            f"from no joint, so the chain from the root {first!r} (line {links[first]}) stops before {them}; add the "
            f"missing joint or fix the <child link=...> that should name {them}", path=path,
            line=links[cut[0]], key=cut[0])
    if not roots and links:
        raise CalibrationError("no root link: the joints form a loop (every link is some joint's child)", path=path)


def check_urdf_structure(text: str, path: str | Path | None = None) -> None:
    """Refuse a URDF (its well-formed XML text) whose joints and links would silently make a smaller robot."""
    robot = _parse(text)
    links = _links(robot, path)
    parent_of: dict[str, str] = {}
    edges: list[tuple[str, str]] = []
    for joint in robot.children:
        if joint.tag != "joint":
            continue
        name = joint.attrs.get("name")
        if not name:
            raise CalibrationError("a <joint> without a name", path=path, line=joint.line)
        parent = _joint_link(joint, "parent", links, path)
        child = _joint_link(joint, "child", links, path)
        edges.append((parent, child))
        if child in parent_of:
            raise CalibrationError(f"joint {name!r}: link {child!r} is already the child of joint "
                                   f"{parent_of[child]!r}; a link hangs from one joint", path=path, line=joint.line)
        parent_of[child] = name
        _check_vectors(joint, path, f"joint {name!r}")
    _check_tree(links, edges, path)
