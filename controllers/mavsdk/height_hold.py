"""Hold the height at which velocity control engaged: a vertical speed added to each body-frame setpoint.

A body-frame velocity setpoint with vertical speed 0 holds nothing: the autopilot tracks its own velocity
estimate, and PX4 SIH climbed from 9.4 m to 12.1 m in 14 s of them. The vectors' contract, ``(vx, vy, t)``,
has no vertical speed, so every vector holds the height: from the autopilot's LOCAL_POSITION_NED, a P correction
toward the height captured when velocity control engaged, bounded, and 0 (the plain setpoint) while that
position is older than :data:`MAX_AGE_S`. The same correction works on PX4, ArduCopter (whose GUIDED holds
its height itself; the correction then stays near 0) and the built-in vehicle.
"""

from __future__ import annotations

import logging
import math
import time

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage

from controllers.mavsdk.calls import Subscriptions
from controllers.mavsdk.pose import parse_pose_message

logger = logging.getLogger(__name__)

GAIN_PER_S = 1.0
"""Vertical speed per metre of height error (PX4's MPC_Z_P is 1.0 too)."""

MAX_CORRECTION_MS = 0.5
"""The largest vertical speed the hold asks for."""

MAX_AGE_S = 0.5
"""A position older than this is not corrected on (the telemetry asks for 10 Hz)."""


class HeightHold:
    """The height target of one controller's velocity control, and the vertical speed that keeps it.

    Args:
        system_id: the autopilot's; LOCAL_POSITION_NED from others is ignored.
    """

    def __init__(self, system_id: int) -> None:
        self._system_id = system_id
        self._down: tuple[float, float] | None = None
        """(down m, time.monotonic()) of the newest position."""
        self._engaged = False
        self._target: float | None = None

    def follow(self, direct: MavlinkDirectAsync, subscriptions: Subscriptions) -> None:
        """Read LOCAL_POSITION_NED until ``subscriptions`` closes."""
        subscriptions.read(direct.subscribe_message("LOCAL_POSITION_NED"), self.on_message, "height-hold")

    def on_message(self, message: MavlinkMessage) -> None:
        parsed = parse_pose_message(message) if message.system_id == self._system_id else None
        if parsed is not None and parsed[0] == "position" and math.isfinite(down := parsed[2][2]):
            self._down = (down, time.monotonic())

    def engage(self) -> None:
        """Velocity control started: hold the height the vehicle is at now (or at the next fresh position)."""
        self._engaged = True
        self._target = None
        self._capture()

    def release(self) -> None:
        """Velocity control ended: nothing to hold."""
        self._engaged = False
        self._target = None

    @property
    def target_down_m(self) -> float | None:
        """The height held, as local NED down (m); None while none is."""
        return self._target

    def vertical_speed(self) -> float:
        """Down speed (m/s) for the next setpoint: toward the held height, 0 without a fresh position."""
        down = self._fresh_down()
        if not self._engaged or down is None:
            return 0.0
        if self._target is None:
            self._capture()
            return 0.0
        return max(-MAX_CORRECTION_MS, min(MAX_CORRECTION_MS, GAIN_PER_S * (self._target - down)))

    def _fresh_down(self) -> float | None:
        if self._down is None or time.monotonic() - self._down[1] > MAX_AGE_S:
            return None
        return self._down[0]

    def _capture(self) -> None:
        self._target = self._fresh_down()
        if self._target is None:
            logger.warning("height hold: no fresh LOCAL_POSITION_NED; the height is held from the next one")
