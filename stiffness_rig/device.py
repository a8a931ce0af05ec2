"""The one-port gauge counter of a ``rodlab.rigprofile/1`` profile, read through the instrument machinery.

A version 1 profile is one ``numeric_line`` instrument (its request, separator, checksum, query / stream)
whose values are the gauges (and a temperature), with the loader on the same port:
:func:`as_instrument_profile` says so, and :class:`GaugeClient` is the :class:`~.instruments.RigClient` of
that. Garbage is counted and logged, never fatal; a device that stops answering is retried, its port
reopened (a replugged USB cable comes back under the same path), and only then does
:class:`~.errors.DeviceError` say what to check.
"""
from __future__ import annotations

from .config import RigProfile
from .instrument_profile import Instrument, InstrumentChannel, InstrumentProfile
from .instruments import RigClient

__all__ = ["GaugeClient", "as_instrument_profile"]

COUNTER = "counter"


def as_instrument_profile(profile: RigProfile) -> InstrumentProfile:
    """The ``rodlab.rigprofile/1`` profile as one ``numeric_line`` instrument named ``counter``."""
    channels = [InstrumentChannel("displacement", str(c.index), c.axis, c.sign, c.scale_mm, "mm")
                for c in profile.channels]
    if profile.temperature_index is not None:
        channels.append(InstrumentChannel("temperature", str(profile.temperature_index), units="degC"))
    config = {"mode": profile.protocol, "request": profile.request.encode("unicode_escape").decode("ascii"),
              "separator": profile.separator, "checksum": profile.checksum, "n_values": profile.n_values}
    ins = Instrument(COUNTER, profile.port, "numeric_line", config, tuple(channels), profile.baudrate,
                     profile.bytesize, profile.parity, profile.stopbits, profile.timeout_s, profile.retries)
    return InstrumentProfile((ins,), COUNTER if profile.loader_command else None, profile.loader_command,
                             profile.loader_ack, profile.path, format="rodlab.rigprofile/1")


class GaugeClient(RigClient):
    """Readings in mm in {T} from the gauge counter of a ``rodlab.rigprofile/1`` profile."""

    def __init__(self, profile: RigProfile, reconnect_attempts: int = 8) -> None:
        super().__init__(as_instrument_profile(profile), reconnect_attempts)
