"""The interface every instrument protocol implements, and the per-instrument settings it declares.

A driver turns one poll of an instrument into named values in the instrument's own units: it writes its
request (if any) on the instrument's :class:`Link` and reads the answer. A line that is not a reading is
:class:`Garbage` (counted, never fatal); no answer within the port's timeout is :class:`NoAnswer`. Retries,
reopening the port and the final clear error are the instrument client's (:mod:`..instruments`), the same for
every protocol.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

__all__ = ["Setting", "SettingError", "Driver", "Link", "Garbage", "NoAnswer", "unescape", "INIT_SETTING"]


class SettingError(ValueError):
    """A protocol setting the driver cannot use; ``key`` names it (dotted inside the instrument)."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


class Garbage(Exception):
    """An answer that is not a reading (bad checksum, wrong format, an error code); ``raw`` is what came."""

    def __init__(self, raw: bytes, why: str = "") -> None:
        shown = f"received {raw[:60]!r}" if raw else ""
        super().__init__("; ".join(p for p in (shown, why) if p) or "an unreadable answer")
        self.raw = raw


class NoAnswer(Exception):
    """Nothing came back within the port's timeout."""


def unescape(text: str) -> str:
    """``"R\\r\\n"`` as written in a TOML profile -> the characters it stands for."""
    return text.encode().decode("unicode_escape")


@dataclass(frozen=True)
class Setting:
    """One protocol setting of an instrument in the profile: key, type (``str``, ``int``, ``float``, ``list``),
    default (None: required), allowed values, one line of help."""

    key: str
    type: type
    default: Any
    help: str
    choices: tuple = ()


class Link:
    """The open port of one instrument as drivers see it (pyserial underneath)."""

    def __init__(self, serial_port) -> None:
        self.serial = serial_port
        self._carry = b""

    def write(self, data: bytes) -> None:
        self.serial.write(data)
        self.serial.flush()

    def readline(self, eol: bytes = b"\n") -> bytes:
        """Bytes up to and including ``eol`` (or what came before the timeout); NoAnswer for nothing."""
        raw = self.serial.read_until(eol)
        if not raw:
            raise NoAnswer()
        return raw

    def latest_line(self, eol: bytes = b"\n") -> bytes:
        """The newest complete line a pushing device has sent (older ones are stale: a reading is of now), or
        the next one to come; NoAnswer for nothing."""
        data = self._carry + self.serial.read(self.serial.in_waiting or 0)
        *complete, self._carry = data.split(eol)
        complete = [c for c in complete if c.strip()]
        if complete:
            return complete[-1] + eol
        raw = self.serial.read_until(eol)
        if not raw:
            raise NoAnswer()
        raw, self._carry = self._carry + raw, b""
        return raw

    def clear_input(self) -> None:
        self._carry = b""
        self.serial.reset_input_buffer()


class Driver:
    """One instrument protocol. Subclasses set ``name``, ``summary``, ``settings``, ``simulator`` and implement
    :meth:`poll`; ``values`` lists the names of the values one poll gives (a channel picks one)."""

    name: ClassVar[str] = ""
    summary: ClassVar[str] = ""
    settings: ClassVar[tuple] = ()
    #: the class name of its simulator in :mod:`..siminstruments`
    simulator: ClassVar[str] = ""
    #: whether a loader command line can share the port (a text protocol)
    text_lines: ClassVar[bool] = True

    def __init__(self, config: dict) -> None:
        self.config = dict(config)

    @property
    def values(self) -> tuple:
        """The names of the values one poll gives (a channel's ``value``)."""
        raise NotImplementedError

    def poll(self, link: Link) -> dict:
        """One reading: {value name: number in the instrument's units}. Raises Garbage or NoAnswer."""
        raise NotImplementedError

    def after_reopen(self) -> None:
        """Called when the port was reopened (a driver holding state on the old port drops it)."""

    def startup(self, link: Link) -> None:
        """Called after each opening of the port: a text driver sends its ``init`` line (remote mode, start
        streaming) and drops what answers it; nothing by default."""
        init = unescape(str(self.config.get("init", "")))
        if not init:
            return
        link.clear_input()
        link.write(init.encode("ascii"))
        try:
            link.readline(unescape(str(self.config.get("eol", "\\n"))).encode("ascii"))   # its acknowledgement, if any
        except NoAnswer:
            pass
        link.clear_input()


#: the ``init`` setting of a text protocol (:meth:`Driver.startup`)
INIT_SETTING = Setting("init", str, "", "sent once after each opening of the port (remote mode, start streaming; "
                                        "its answer is dropped); not a zero or tare: rodlab zeroes each series "
                                        "from its unloaded start hold, and a tare at a reconnect would shift it")
