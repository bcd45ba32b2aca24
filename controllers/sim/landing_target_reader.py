"""Precision landing in the simulator: where the pad is, from LANDING_TARGET, as each autopilot reads it.

* ArduPilot dialect (``AC_PrecLand_Companion``, ``PLND_ENABLED=1``): ``MAV_FRAME_BODY_FRD`` (or ``LOCAL_FRD``)
  only; angles give the line of sight ``(-tan(angle_y), tan(angle_x), 1)`` in the body frame, ``position_valid``
  gives ``x, y, z`` in it. Turned by the vehicle's attitude, it meets the pad ``distance`` away (or, without one,
  at the ground: the simulator's rangefinder).
* PX4 dialect (``landing_target_pose``): ``position_valid = 1`` in ``MAV_FRAME_LOCAL_NED``, always taken; its
  Precision Land mode (PRECLAND) lands on it, a plain LAND (also ``MAV_CMD_NAV_LAND`` with param 2) does not.

A target is used for :data:`STALE_S` after it arrived; LAND then flies over the newest pad estimate while it
descends and, once the target is stale, keeps to the last estimate.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from dataclasses import asdict, dataclass

import numpy as np
from pymavlink.dialects.v20 import common as mavlink

from controllers.landing_target_message import rotation_ned_body

logger = logging.getLogger(__name__)

STALE_S = 1.0
"""ArduPilot drops a landing target older than this (``AC_PrecLand``: 1 s without a measurement)."""

COMPANION = 1
"""ArduPilot's PLND_TYPE for a companion computer's LANDING_TARGET."""

_BODY_FRAMES = (mavlink.MAV_FRAME_BODY_FRD, mavlink.MAV_FRAME_LOCAL_FRD)


@dataclass(frozen=True, slots=True)
class LandingTargetRecord:
    """Arrival of one LANDING_TARGET, stamped with time.monotonic_ns() when the datagram was read."""

    t_mono_ns: int
    time_usec: int
    frame: int
    position_valid: int
    used: bool
    """The dialect read a pad position from it (else it was dropped, as the autopilot would)."""

    def as_dict(self) -> dict[str, int | bool]:
        return asdict(self)


class PadEstimate:
    """The newest pad position (north, east) from LANDING_TARGET, for one dialect.

    Args:
        ardupilot: read the message as ArduPilot does (else as PX4 does).
    """

    def __init__(self, ardupilot: bool) -> None:
        self.ardupilot = ardupilot
        self.enabled = not ardupilot
        """ArduPilot: PLND_ENABLED; PX4 always takes the target (its PRECLAND mode decides to land on it)."""
        self.source_type = COMPANION
        """ArduPilot: PLND_TYPE; only a companion's (1) LANDING_TARGET is read."""
        self.position: np.ndarray | None = None
        self.received_ns = 0
        self.received = 0
        self.rejected = 0
        self.log: deque[LandingTargetRecord] = deque(maxlen=20_000)
        """Every LANDING_TARGET that arrived, oldest first (the truth channel's ``landing_targets``)."""

    def on_message(self, msg: mavlink.MAVLink_message, t_ns: int, pos: np.ndarray,
                   attitude: tuple[float, float, float]) -> None:
        """A LANDING_TARGET that arrived at ``t_ns`` while the vehicle was at ``pos`` (NED) with ``attitude``
        (roll, pitch, yaw radians)."""
        pad = self._ardupilot(msg, pos, attitude) if self.ardupilot else self._px4(msg)
        self.log.append(LandingTargetRecord(t_ns, int(msg.time_usec), int(msg.frame), int(msg.position_valid),
                                            pad is not None))
        if pad is None:
            self.rejected += 1
            return
        self.position, self.received_ns = pad, t_ns
        self.received += 1

    def pad(self, now_ns: int) -> np.ndarray | None:
        """The pad's (north, east) while enabled and a target arrived within :data:`STALE_S`."""
        if not self.enabled or self.source_type != COMPANION or self.position is None:
            return None
        if now_ns - self.received_ns > STALE_S * 1e9:
            return None
        return self.position

    @staticmethod
    def _ardupilot(msg: mavlink.MAVLink_message, pos: np.ndarray,
                   attitude: tuple[float, float, float]) -> np.ndarray | None:
        if msg.frame not in _BODY_FRAMES:
            logger.info("SimVehicle: Plnd: Frame not supported (%d)", msg.frame)
            return None
        if msg.position_valid:
            if msg.distance <= 0:
                return None
            los = np.array([msg.x, msg.y, msg.z]) / msg.distance
        else:
            los = np.array([-math.tan(msg.angle_y), math.tan(msg.angle_x), 1.0])
        ned = rotation_ned_body(*(math.degrees(a) for a in attitude)) @ (los / np.linalg.norm(los))
        if msg.distance > 0:
            return (pos + ned * msg.distance)[:2]
        if ned[2] <= 1e-6:
            return None
        return (pos + ned * (-pos[2] / ned[2]))[:2]  # the ray meets the ground (d = 0)

    @staticmethod
    def _px4(msg: mavlink.MAVLink_message) -> np.ndarray | None:
        if not (msg.position_valid and msg.frame == mavlink.MAV_FRAME_LOCAL_NED):
            return None  # PX4 sends angles-only targets to its IR-LOCK path, which the simulator does not have
        return np.array([msg.x, msg.y], float)
