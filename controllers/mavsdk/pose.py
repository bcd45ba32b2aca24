"""The vehicle's pose at a camera's pace: LOCAL_POSITION_NED, ATTITUDE and (where there is a gimbal)
GIMBAL_DEVICE_ATTITUDE_STATUS from any MAVLink autopilot.

Asked for at :data:`POSE_RATE_HZ` with MAV_CMD_SET_MESSAGE_INTERVAL, as a ground station asks
(PX4, ArduPilot and the built-in simulator all honour it; ArduPilot's REQUEST_DATA_STREAM, sent at
connect, would reset it, so it is sent after). Each sample is stamped with the time it was valid:
the autopilot's ``time_boot_ms`` mapped onto this computer's ``time.monotonic_ns()`` by
:class:`BootClock`, so the delivery delay through MAVSDK and the event loop does not shift it.
"""

from __future__ import annotations

import asyncio
import collections
import json
import logging
import math
import time
from collections.abc import AsyncIterator
from typing import Literal

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage

from controllers.base import PoseSample
from controllers.mavsdk.calls import Subscriptions
from controllers.mavsdk.mavlink_commands import command_long, send_command
from controllers.quaternion import euler

logger = logging.getLogger(__name__)

MAV_CMD_SET_MESSAGE_INTERVAL = 511
POSE_MESSAGES = {"LOCAL_POSITION_NED": 32, "ATTITUDE": 30, "GIMBAL_DEVICE_ATTITUDE_STATUS": 285}
"""Message name -> MAVLink id."""

POSE_RATE_HZ = 50.0
"""Rate asked for each pose message: a 30 FPS camera then interpolates between samples 20 ms apart."""

CLOCK_WINDOW_S = 10.0
"""The clock offset is the smallest (receive time - autopilot time) seen over this window."""

CLOCK_RESET_S = 1.0
"""An offset this much above the estimate means the autopilot's clock restarted: estimate afresh."""


class BootClock:
    """Maps an autopilot's ``time_boot_ms`` onto ``time.monotonic_ns()``.

    The offset is the minimum of (receive time - boot time) over :data:`CLOCK_WINDOW_S`: the sample
    that arrived fastest bounds the transport delay best. Slow drift is followed by the window.
    """

    def __init__(self) -> None:
        self._offsets: collections.deque[tuple[int, int]] = collections.deque()  # (received_ns, offset), rising

    def to_mono_ns(self, boot_ms: int, received_mono_ns: int) -> int:
        """The monotonic time of an autopilot time ``boot_ms`` that arrived at ``received_mono_ns``."""
        self.observe(boot_ms, received_mono_ns)
        return boot_ms * 1_000_000 + self._offsets[0][1]

    def observe(self, boot_ms: int, received_mono_ns: int) -> None:
        """One message stamped ``boot_ms`` by the autopilot arrived at ``received_mono_ns``."""
        offset = received_mono_ns - boot_ms * 1_000_000
        window = self._offsets
        if window and offset - window[0][1] > CLOCK_RESET_S * 1e9:
            window.clear()  # the autopilot rebooted: its clock started again from zero
        while window and window[-1][1] >= offset:
            window.pop()
        window.append((received_mono_ns, offset))
        while received_mono_ns - window[0][0] > CLOCK_WINDOW_S * 1e9:
            window.popleft()

    def boot_us(self, mono_ns: int) -> int | None:
        """``mono_ns`` (time.monotonic_ns()) on the autopilot's clock, µs since its boot; None before a message."""
        if not self._offsets:
            return None
        return (mono_ns - self._offsets[0][1]) // 1000


def message_interval_command(target_system: int, message_id: int, rate_hz: float) -> MavlinkMessage:
    """SET_MESSAGE_INTERVAL: ``message_id`` every ``1 / rate_hz`` seconds."""
    return command_long(target_system, MAV_CMD_SET_MESSAGE_INTERVAL, message_id, 1e6 / rate_hz)


async def request_pose_rate(direct: MavlinkDirectAsync, target_system: int, rate_hz: float = POSE_RATE_HZ,
                            timeout_s: float = 10.0) -> None:
    """Ask for both pose messages at ``rate_hz``; a refusal, or no answer within ``timeout_s``, is logged (the
    default rate still works)."""

    async def one(name: str, message_id: int) -> None:
        try:
            await send_command(direct, message_interval_command(target_system, message_id, rate_hz))
        except Exception as exc:  # noqa: BLE001 - refused or unanswered: the camera still gets samples
            logger.warning("autopilot refused %s at %g Hz (%s); the sim: camera interpolates what comes", name,
                           rate_hz, exc)

    try:
        async with asyncio.timeout(timeout_s):
            await asyncio.gather(*(one(name, message_id) for name, message_id in POSE_MESSAGES.items()))
    except TimeoutError:
        logger.warning("pose rate: no answer within %.0f s; keeping the current rates", timeout_s)


YAW_IN_EARTH_FRAME, YAW_IN_VEHICLE_FRAME, YAW_LOCK = 64, 32, 16
"""GIMBAL_DEVICE_FLAGS that say which frame a gimbal's yaw is in (older devices: YAW_LOCK alone means earth)."""

PoseKind = Literal["position", "attitude", "gimbal", "gimbal_earth"]


def parse_pose_message(message: MavlinkMessage) -> tuple[PoseKind, int, tuple[float, float, float]] | None:
    """(kind, time_boot_ms, values) from a LOCAL_POSITION_NED, ATTITUDE or GIMBAL_DEVICE_ATTITUDE_STATUS message;
    None if malformed."""
    try:
        fields = json.loads(message.fields_json)
        boot_ms = int(fields["time_boot_ms"])
        if message.message_name == "LOCAL_POSITION_NED":
            return "position", boot_ms, (float(fields["x"]), float(fields["y"]), float(fields["z"]))
        if message.message_name == "GIMBAL_DEVICE_ATTITUDE_STATUS":
            flags = int(fields["flags"])
            earth = bool(flags & YAW_IN_EARTH_FRAME or not flags & YAW_IN_VEHICLE_FRAME and flags & YAW_LOCK)
            roll, pitch, yaw = (math.degrees(a) for a in euler(fields["q"]))
            return ("gimbal_earth" if earth else "gimbal"), boot_ms, (roll, pitch, yaw)
        roll, pitch, yaw = (math.degrees(float(fields[name])) for name in ("roll", "pitch", "yaw"))
        return "attitude", boot_ms, (roll, pitch, yaw)
    except (ValueError, KeyError, TypeError):
        return None


async def pose_samples(direct: MavlinkDirectAsync, system_id: int, stop: asyncio.Event,
                       subscriptions: Subscriptions) -> AsyncIterator[PoseSample]:
    """Position and attitude samples from ``system_id`` as they arrive, until ``stop`` is set."""
    queue: asyncio.Queue[PoseSample | None] = asyncio.Queue()
    clock = BootClock()

    def on_message(message: MavlinkMessage) -> None:
        received = time.monotonic_ns()
        parsed = parse_pose_message(message) if message.system_id == system_id else None
        if parsed is not None:
            kind, boot_ms, values = parsed
            queue.put_nowait(PoseSample(kind, clock.to_mono_ns(boot_ms, received), values))

    async def end_on_stop() -> None:
        await stop.wait()
        queue.put_nowait(None)

    tasks = [subscriptions.read(direct.subscribe_message(name), on_message, f"pose-{name}") for name in POSE_MESSAGES]
    tasks.append(asyncio.create_task(end_on_stop()))
    try:
        while (sample := await queue.get()) is not None:
            yield sample
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
