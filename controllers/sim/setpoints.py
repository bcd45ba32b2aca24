"""Decoding SET_POSITION_TARGET_LOCAL_NED the way PX4 reads it (type_mask, frames)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from pymavlink.dialects.v20 import common as mavlink

from controllers.sim.guidance import OffboardSetpoint
from controllers.sim.physics import Multicopter

IGNORE_POSITION = 0b111
IGNORE_VELOCITY = 0b111 << 3
IGNORE_YAW = 1 << 10
IGNORE_YAW_RATE = 1 << 11
BODY_FRAMES = frozenset({mavlink.MAV_FRAME_BODY_NED, mavlink.MAV_FRAME_BODY_OFFSET_NED, mavlink.MAV_FRAME_BODY_FRD})
LOCAL_FRAMES = frozenset({mavlink.MAV_FRAME_LOCAL_NED, mavlink.MAV_FRAME_LOCAL_OFFSET_NED}) | BODY_FRAMES


@dataclass(frozen=True, slots=True)
class SetpointRecord:
    """Arrival of one offboard setpoint, stamped with time.monotonic_ns() when the datagram was read."""

    t_mono_ns: int
    vx: float
    vy: float
    vz: float
    frame: int

    def as_dict(self) -> dict[str, float | int]:
        return asdict(self)


def _finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)


def parse_local_ned(
    msg: mavlink.MAVLink_message, t_ns: int, vehicle: Multicopter
) -> tuple[SetpointRecord, OffboardSetpoint | None]:
    """The arrival record, and the setpoint PX4 would follow (None if the frame or values are unusable).

    Body frames rotate velocities by the yaw at the time of use (heading frame, as PX4 does);
    body-frame positions are offsets from the current position, rotated by the current yaw.
    """
    mask, frame = msg.type_mask, msg.coordinate_frame
    record = SetpointRecord(t_ns, float(msg.vx), float(msg.vy), float(msg.vz), int(frame))
    if frame not in LOCAL_FRAMES:
        return record, None
    body = frame in BODY_FRAMES
    velocity = position = None
    if mask & IGNORE_VELOCITY != IGNORE_VELOCITY:
        if not _finite(msg.vx, msg.vy, msg.vz):
            return record, None
        velocity = (float(msg.vx), float(msg.vy), float(msg.vz))
    if mask & IGNORE_POSITION != IGNORE_POSITION:
        if not _finite(msg.x, msg.y, msg.z):
            return record, None
        x, y, z = float(msg.x), float(msg.y), float(msg.z)
        if body:
            c, s = math.cos(vehicle.yaw), math.sin(vehicle.yaw)
            x, y = x * c - y * s, x * s + y * c
        if frame != mavlink.MAV_FRAME_LOCAL_NED:
            x, y, z = x + vehicle.pos[0], y + vehicle.pos[1], z + vehicle.pos[2]
        position = (x, y, z)
    yaw = float(msg.yaw) if not mask & IGNORE_YAW and math.isfinite(msg.yaw) else None
    yaw_rate = float(msg.yaw_rate) if not mask & IGNORE_YAW_RATE and math.isfinite(msg.yaw_rate) else None
    if velocity is None and position is None:
        velocity = (0.0, 0.0, 0.0)
    return record, OffboardSetpoint(velocity, body, position, yaw, yaw_rate)
