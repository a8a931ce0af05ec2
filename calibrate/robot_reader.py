"""What a robot file reader provides (:class:`RobotFormat`): its suffix, how to read a file and how to name the
format. A reader module ``calibrate/robot_NAME.py`` declares its ``ROBOT_FORMAT``; the registry
(:data:`rodlab.calibrate.robot_formats.ROBOT_READERS`) finds it. Kept apart from the registry so that a reader
module never imports the registry that imports it.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .robot import Robot

__all__ = ["RobotFormat"]


@dataclass(frozen=True)
class RobotFormat:
    """One kind of robot file: how to read it and how to name it.

    Attributes
    ----------
    read : reader(path, base_link, tip_link) -> :class:`Robot`
    describes : the format in a help text, e.g. ``"a URDF (xacro expanded)"``
    format_id : what ``rodlab validate`` calls a file of this kind when it has no JSON schema (``"urdf"``); ``None``
        when the file names its format itself (a robot TOML's ``format`` key, checked by its schema)
    suffix : the file suffix it reads, lower case with its dot (``".urdf"``)
    """

    read: Callable[..., Robot]
    describes: str
    format_id: str | None = None
    suffix: str = ""

    def __call__(self, path, base_link: str | None = None, tip_link: str | None = None) -> Robot:
        return self.read(path, base_link, tip_link)
