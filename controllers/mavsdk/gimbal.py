"""The gimbal through MAVSDK's Gimbal plugin (MAVLink gimbal protocol v2): take control, stream setpoints, release;
and the gimbal's attitude as telemetry.

MAVSDK finds a gimbal by asking every component for GIMBAL_MANAGER_INFORMATION, a few seconds after connecting; the
first it lists is the one used (:meth:`MavsdkGimbal.watch_list` from the connection on).
Setpoints are streamed (GIMBAL_MANAGER_SET_ATTITUDE, ``SendMode.STREAM``: the send mode for setpoints above 1 Hz;
``ONCE`` is a command acknowledged each time), yaw following the vehicle (``YAW_FOLLOW``: a yaw angle is from the
nose). Autopilots: ArduPilot >= 4.3 with a mount (``MNT1_TYPE``), PX4 with ``MNT_MODE_IN=4`` (gimbal v2 input).
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Awaitable, Callable
from typing import Any

from mavsdk.asyncio import System
from mavsdk.asyncio.plugins.gimbal import ControlMode, GimbalAsync, GimbalMode, SendMode

from controllers.errors import NotSupported
from controllers.mavsdk.calls import Subscriptions

logger = logging.getLogger(__name__)

Command = Callable[[str, Callable[[], Awaitable[Any]]], Awaitable[Any]]
"""The controller's bounded MAVSDK call: ``command(name, call)``, errors translated to ControllerErrors."""

RATE, ANGLE = "rate", "angle"

TELEMETRY_HZ = 10.0
"""The gimbal's attitude goes to telemetry at most this often (the ``sim:`` camera reads it at the pose's rate from
GIMBAL_DEVICE_ATTITUDE_STATUS itself; every telemetry update is a telemetry.csv row)."""

DISCOVERY_WAIT_S = 10.0
"""How long after connecting MAVSDK may take to list a gimbal: it asks each component once per heartbeat (measured:
the built-in simulator's within 2 s of connecting, ArduCopter's and PX4's SITL in 5 s). A setpoint waits for it
until then; later, a vehicle that listed none has none."""


def attitude_update(attitude: Any) -> dict[str, float]:
    """A gimbal :class:`~mavsdk.plugins.gimbal.Attitude` as telemetry: roll and pitch from the horizon, yaw from
    north (MAVSDK's ``euler_angle_north``), degrees; {} while MAVSDK does not know the vehicle's heading yet."""
    angles = attitude.euler_angle_north
    values = (angles.roll_deg, angles.pitch_deg, angles.yaw_deg)
    if not all(isinstance(v, float | int) and math.isfinite(v) for v in values):
        return {}
    return dict(zip(("gimbal_roll_deg", "gimbal_pitch_deg", "gimbal_yaw_deg"), map(float, values), strict=True))


class MavsdkGimbal:
    """The vehicle's first gimbal, driven through one controller's bounded calls.

    Args:
        system: the connected MAVSDK system.
        command: the controller's bounded call (timeouts, errors translated).
    """

    def __init__(self, system: System, command: Command) -> None:
        self._plugin = GimbalAsync(system)
        self._command = command
        self.gimbal_id: int | None = None
        """MAVSDK's id of the first gimbal it listed (None: none found yet)."""
        self._found = asyncio.Event()
        self._listing_since = time.monotonic()
        """When MAVSDK began looking for gimbals (built at connection, with :meth:`watch_list` called at once)."""
        self.controlled = False
        """Control was asked for (and not released since)."""

    async def point(self, mode: str, pitch: float, yaw: float) -> None:
        """Take control of the gimbal if not held yet, then stream this setpoint: ``mode`` ``rate`` (deg/s) or
        ``angle`` (degrees; yaw from the nose); pitch positive up.

        Raises:
            NotSupported: the vehicle has no gimbal MAVSDK can find.
            ControllerError: taking control or sending failed; the link is lost.
        """
        if mode not in (RATE, ANGLE) or not (math.isfinite(pitch) and math.isfinite(yaw)):
            raise ValueError(f"gimbal setpoint {mode} ({pitch}, {yaw}): mode rate or angle, finite values")
        gimbal_id = await self._find()
        if not self.controlled:
            self.controlled = True  # before the answer: a take_control the vehicle got is released even if it timed out
            await self._command("gimbal take_control",
                                lambda: self._plugin.take_control(gimbal_id, ControlMode.PRIMARY))
            logger.info("MavsdkGimbal: control of gimbal %d taken", gimbal_id)
        if mode == RATE:
            await self._command("gimbal set_angular_rates", lambda: self._plugin.set_angular_rates(
                gimbal_id, 0.0, pitch, yaw, GimbalMode.YAW_FOLLOW, SendMode.STREAM))
        else:
            await self._command("gimbal set_angles", lambda: self._plugin.set_angles(
                gimbal_id, 0.0, pitch, yaw, GimbalMode.YAW_FOLLOW, SendMode.STREAM))

    async def release(self) -> None:
        """Stop the gimbal (zero rates) and release control; nothing when control is not held.

        Raises:
            ControllerError: the release was not acknowledged (control is counted as released all the same: the
                manager gives it back to whoever asks next).
        """
        if not self.controlled or self.gimbal_id is None:
            return
        gimbal_id, self.controlled = self.gimbal_id, False
        try:
            await self._command("gimbal stop", lambda: self._plugin.set_angular_rates(
                gimbal_id, 0.0, 0.0, 0.0, GimbalMode.YAW_FOLLOW, SendMode.STREAM))
        finally:
            await self._command("gimbal release_control", lambda: self._plugin.release_control(gimbal_id))
            logger.info("MavsdkGimbal: gimbal %d stopped and control released", gimbal_id)

    def read_attitude(self, subscriptions: Subscriptions,
                      on_update: Callable[[dict[str, Any]], None]) -> asyncio.Task[None]:
        """Call ``on_update`` with each attitude report as telemetry (:func:`attitude_update`) in a task (ended by
        cancelling it or closing ``subscriptions``)."""

        last = -math.inf

        def put(attitude: Any) -> None:
            nonlocal last
            now = time.monotonic()
            if now - last < 1 / TELEMETRY_HZ or self.gimbal_id not in (None, attitude.gimbal_id):
                return
            if update := attitude_update(attitude):
                last = now
                on_update(update)

        return subscriptions.read(self._plugin.subscribe_attitude(), put, "gimbal-attitude")

    def watch_list(self, subscriptions: Subscriptions) -> None:
        """Keep :attr:`gimbal_id` as MAVSDK discovers gimbals (call once, at connection)."""

        def put(found: Any) -> None:
            gimbals = list(getattr(found, "gimbals", None) or [])
            if gimbals and self.gimbal_id is None:
                self.gimbal_id = int(gimbals[0].gimbal_id)
                self._found.set()
                logger.info("MavsdkGimbal: gimbal %d found (%s)", self.gimbal_id,
                            getattr(gimbals[0], "model_name", "") or "unnamed")

        subscriptions.read(self._plugin.subscribe_gimbal_list(), put, "gimbal-list")

    async def _find(self) -> int:
        """The gimbal's id; waits for MAVSDK's listing until :data:`DISCOVERY_WAIT_S` after connection, no longer."""
        if self.gimbal_id is None:
            try:
                async with asyncio.timeout(self._listing_left()):
                    await self._found.wait()
            except TimeoutError:
                raise NotSupported("gimbal: the vehicle has no gimbal MAVSDK can find (gimbal protocol v2: ArduPilot "
                                   "with a mount, MNT1_TYPE; PX4 with MNT_MODE_IN=4)") from None
        assert self.gimbal_id is not None
        return self.gimbal_id

    def _listing_left(self) -> float:
        """Seconds MAVSDK may still take to list a gimbal."""
        return max(0.0, self._listing_since + DISCOVERY_WAIT_S - time.monotonic())
