"""Which autopilot a controller reached: PX4, ArduPilot, or one the platform does not know."""

from __future__ import annotations

from enum import StrEnum


class Autopilot(StrEnum):
    """An autopilot's kind; the values are what the sim's ``--autopilot`` and the tests spell."""

    PX4 = "px4"
    ARDUPILOT = "ardupilot"
    UNKNOWN = "unknown"

    @property
    def label(self) -> str:
        """``PX4``, ``ArduPilot`` or ``unknown autopilot``: the name the operator reads."""
        return _LABELS[self]


_LABELS = {Autopilot.PX4: "PX4", Autopilot.ARDUPILOT: "ArduPilot", Autopilot.UNKNOWN: "unknown autopilot"}
