"""What a refused calibration's files may have mixed up (:class:`Mixup`): a joint's readings reversed, two joint or
reading columns exchanged, two clamping positions swapped, a joint's zero or a coupled convention, fixture angles in
radians; each with the wording that names it and its fix. The search for one is :mod:`calibrate.mixups`.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Mixup"]

_READ = ("x_mm", "y_mm", "z_mm")


@dataclass(frozen=True)
class Mixup:
    """joint : 1-based joint whose readings are reversed, or None; positions : the two clamping positions whose
    labels are swapped, or None; rms_mm : the identification's rms per reading [mm] with the mix-up undone;
    rms_given_mm : the rms as the files were given [mm]; readings : the two reading columns (0-2: x_mm, y_mm, z_mm)
    exchanged, or the one reading column negated (a 1-tuple), or None; target_change : (the first data row of the
    second part (1-based), each part's registered nominal misfit [mm]) of instrument points whose target or tool
    changed part-way through, or None; sensor : (1-based sensor, its zero [mm]) of raw device readings that read
    reversed, or None; sensors_exchanged : the two raw sensor columns (1-based) exchanged, or None."""

    joint: int | None
    positions: tuple | None
    rms_mm: float
    rms_given_mm: float
    fixture_radians: bool = False
    columns: tuple | None = None
    given_is_nominal: bool = False
    zero_offset: tuple | None = None
    coupling: tuple | None = None
    alternatives: tuple = ()
    readings: tuple | None = None
    target_change: tuple | None = None
    sensor: tuple | None = None
    sensors_exchanged: tuple | None = None
    radians_position: int | None = None

    def __post_init__(self) -> None:
        kinds = ((self.joint is not None) + (self.positions is not None) + self.fixture_radians
                 + (self.columns is not None) + (self.zero_offset is not None) + (self.coupling is not None)
                 + (self.readings is not None) + (self.target_change is not None) + (self.sensor is not None)
                 + (self.sensors_exchanged is not None))
        if kinds != 1:
            raise ValueError("Mixup: give one of a joint, a pair of positions, a pair of joint columns, a zero offset "
                             "(joint, deg), a coupling (joint a, joint b, sign), a pair of reading columns, a "
                             "reversed sensor, two sensor columns exchanged or fixture_radians")

    @property
    def label(self) -> str:
        if self.target_change is not None:
            return f"target changed at data row {self.target_change[0]}"
        if self.fixture_radians:
            return ("fixture angles read as radians" if self.radians_position is None else
                    f"position {self.radians_position}'s fixture angles read as radians")
        if self.sensor is not None:
            return f"sensor {self.sensor[0]} reversed"
        if self.sensors_exchanged is not None:
            return f"columns s{self.sensors_exchanged[0]}_mm and s{self.sensors_exchanged[1]}_mm exchanged"
        if self.readings is not None and len(self.readings) == 1:
            return f"column {_READ[self.readings[0]]} negated"
        if self.readings is not None:
            return f"columns {_READ[self.readings[0]]} and {_READ[self.readings[1]]} exchanged"
        if self.zero_offset is not None:
            return f"q{self.zero_offset[0]} {self.zero_offset[1]:+g} deg"
        if self.coupling is not None:
            a, b, sign = self.coupling
            return f"q{b} {'+' if sign > 0 else '-'} q{a}"
        if self.columns is not None:
            return f"columns q{self.columns[0]} and q{self.columns[1]} exchanged"
        return (f"joint {self.joint} negated" if self.joint is not None else
                f"positions {self.positions[0]} and {self.positions[1]} swapped")

    @property
    def column_key(self) -> str:
        """The joint column(s) of the readings file to correct (a joint mix-up)."""
        if self.columns is not None:
            return f"q{self.columns[0]}, q{self.columns[1]}"
        if self.readings is not None:
            return ", ".join(_READ[k] for k in self.readings)
        if self.sensor is not None:
            return f"s{self.sensor[0]}_mm"
        if self.sensors_exchanged is not None:
            return ", ".join(f"s{k}_mm" for k in self.sensors_exchanged)
        if self.target_change is not None:
            return "x_mm, y_mm, z_mm"
        k = (self.joint if self.joint is not None else self.zero_offset[0] if self.zero_offset is not None
             else self.coupling[1])
        return f"q{k}"

    def reason(self) -> str:
        if not self.alternatives:
            return self._reason()
        return (f"{self._reason()}; the readings fit the nominal model as well with "
                f"{' or '.join(self.alternatives)}, which they cannot tell from it: check which applies")

    def _reason(self) -> str:
        given = (f"{self.rms_given_mm:.1f} mm" if self.rms_given_mm >= 1.0 else f"{self.rms_given_mm * 1e3:.1f} um")
        given = (f"the nominal model misses them by {given} rms as given" if self.given_is_nominal else
                 f"as given {given}")
        fit = (f"the data fit to {self.rms_mm * 1e3:.1f} um rms per reading ({given}) with every parameter within "
               "its bounds")
        if self.target_change is not None:
            k, a, b = self.target_change
            return (f"the points before data row {k} (the {k}th row after the header, comments not counted) and "
                    f"from it on each fit the nominal model on their own ({a:.1f} "
                    f"and {b:.1f} mm rms, base and tool registered for each) but not together ({self.rms_given_mm:.1f} "
                    f"mm): the target or tool changed at data row {k} (two reflectors, a re-mounted target); give each "
                    "part its own file and calibrate each, or measure again with one target")
        if self.fixture_radians and self.radians_position is not None:
            return (f"the fixture file's angles a, b, c of position {self.radians_position} look like radians (the "
                    f"other positions' are degrees): read as radians {fit}; the format's angles are degrees: convert "
                    "them (degrees = radians x 180 / pi) and run again")
        if self.fixture_radians:
            return (f"the fixture file's angles a, b, c look like radians: read as radians {fit}; the format's angles "
                    "are degrees: convert them (degrees = radians x 180 / pi) and run again")
        if self.sensor is not None:
            k, zero = self.sensor
            return (f"sensor {k}'s readings look reversed (the sensor counting the other way, or its channel "
                    f"exported with the other sign): with s{k}_mm mirrored about its zero ({zero:g} mm) {fit}; "
                    f"flip the sign the device file gives it (sensors[{k}].reading_sign: -1, format rodlab.device/2; "
                    f"or 1, removing a -1 the file already has), or write its readings as {2 * zero:g} - s{k}_mm")
        if self.sensors_exchanged is not None:
            a, b = self.sensors_exchanged
            return _exchanged(f"s{a}_mm", f"s{b}_mm", fit, f" than the device file's sensors[{a}] and [{b}]",
                              " (or the two sensors' entries in the device file)")
        if self.readings is not None and len(self.readings) == 1:
            a = _READ[self.readings[0]]
            return (f"the {a} column looks negated (the device's {a[0]} sensor wired or exported with the other sign: "
                    f"a mirrored, left-handed reading frame no clamping pose can turn into the device's): with {a} "
                    f"negated {fit}; check the sign of the device's {a[0]} channel and negate the {a} column")
        if self.readings is not None:
            return _exchanged(*(_READ[k] for k in self.readings), fit)
        if self.zero_offset is not None:
            k, deg = self.zero_offset
            return (f"joint {k}'s zero differs from the robot file's by {deg:+g} deg: with {deg:+g} deg added to q{k} "
                    f"{fit}; the controller counts joint {k} from another zero than the robot file: add {deg:+g} deg "
                    f"to the q{k} column (or correct the robot file's joint offset)")
        if self.coupling is not None:
            a, b, sign = self.coupling
            op = "+" if sign > 0 else "-"
            return (f"q{b} looks read against joint {a} (a coupled convention: a FANUC controller gives J3 against the "
                    f"horizontal, not against the upper arm): with q{b} {op} q{a} {fit}; convert the q{b} column to "
                    f"q{b} {op} q{a} before calibrating")
        if self.columns is not None:
            a, b = self.columns
            return (f"the q{a} and q{b} columns look exchanged against the robot file's joints {a} and {b}: with them "
                    f"swapped back {fit}; check the column order of the controller's export and swap them")
        if self.joint is not None:
            k = self.joint
            return (f"joint {k}'s readings run the other way than the robot file's joint {k}: with them negated {fit}; "
                    f"check the sign of joint {k} in the controller's export and in the robot file (its axis "
                    f"direction), and negate the q{k} column or correct the robot file")
        a, b = self.positions
        return (f"clamping positions {a} and {b} look swapped between the campaign and the fixture file: with their "
                f"labels exchanged {fit}; check which clamping each block of the campaign was recorded at and "
                f"correct the position column or the fixture file")


def _exchanged(a: str, b: str, fit: str, against: str = "", also: str = "") -> str:
    """The reason of two reading columns ``a`` and ``b`` exchanged (``fit``: what undoing it gives)."""
    return (f"the {a} and {b} columns look exchanged (the device's sensors wired or exported in another order"
            f"{against}): with them swapped back {fit}; check the device's channel order and swap the columns{also}")
