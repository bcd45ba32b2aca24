"""MAVSDK telemetry streams merged into one stream of partial updates keyed by Telemetry fields.

Requested rates (``set_rate_*`` sends MAV_CMD_SET_MESSAGE_INTERVAL; ArduPilot additionally gets
REQUEST_DATA_STREAM from the controller, because it sends nothing until asked):

=================================================  =======
position, attitude, NED velocity, local position    10 Hz
downward rangefinder (DISTANCE_SENSOR), if any      10 Hz
height above the terrain (ALTITUDE), if reported    10 Hz (ArduPilot: TERRAIN_REPORT, its streams' rate)
in-air / landed state, home                         2 Hz
battery, GPS info                                   1 Hz
armed, health (from HEARTBEAT, SYS_STATUS)          as the autopilot sends them (~1 Hz)
heartbeat age (computed here)                       1 Hz
=================================================  =======
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import AsyncGenerator, AsyncIterator, Callable, Sequence
from typing import Any

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from controllers.mavsdk.calls import Subscriptions
from controllers.mavsdk.link_quality import link_readers
from controllers.mavsdk.terrain import from_altitude, terrain_reports

logger = logging.getLogger(__name__)

RATES_HZ: dict[str, float] = {
    "position": 10.0,
    "attitude_euler": 10.0,
    "velocity_ned": 10.0,
    "position_velocity_ned": 10.0,
    "distance_sensor": 10.0,
    "altitude": 10.0,
    "in_air": 2.0,
    "landed_state": 2.0,
    "home": 1.0,
    "battery": 1.0,
    "gps_info": 1.0,
}
"""``TelemetryAsync.set_rate_<name>`` -> Hz."""

HEARTBEAT_TICK_S = 1.0
"""How often the merged stream reports the heartbeat age, also while the link is down."""

Update = dict[str, Any]


def _num(value: float) -> float | None:
    """MAVSDK reports 'not known yet' as NaN; Telemetry uses None."""
    return None if value is None or math.isnan(value) else float(value)


def from_position(p: Any) -> Update:
    """The vehicle's global position; latitude and longitude None while both are exactly 0 (ArduPilot's
    GLOBAL_POSITION_INT before its first fix), as when MAVSDK says NaN."""
    lat, lon = _num(p.latitude_deg), _num(p.longitude_deg)
    if lat == 0.0 and lon == 0.0:
        lat = lon = None
    return {"lat_deg": lat, "lon_deg": lon, "abs_alt_m": _num(p.absolute_altitude_m),
            "rel_alt_m": _num(p.relative_altitude_m)}


def from_attitude_euler(a: Any) -> Update:
    update: Update = {"roll_deg": _num(a.roll_deg), "pitch_deg": _num(a.pitch_deg)}
    update["yaw_deg"] = _num(a.yaw_deg)
    if a.timestamp_us:
        # MAVSDK fills it from ATTITUDE.time_boot_ms: the autopilot's own clock.
        update["fc_boot_ms"] = int(a.timestamp_us) // 1000
    return update


def from_velocity_ned(v: Any) -> Update:
    return {"vn_ms": _num(v.north_m_s), "ve_ms": _num(v.east_m_s), "vd_ms": _num(v.down_m_s)}


def from_position_velocity_ned(pv: Any) -> Update:
    p = pv.position
    position = {"north_m": _num(p.north_m), "east_m": _num(p.east_m), "down_m": _num(p.down_m)}
    return position | from_velocity_ned(pv.velocity)


def from_distance_sensor(d: Any) -> Update:
    """A downward sensor's reading, None outside its (minimum, maximum) range; other sensors are ignored.

    MAVSDK turns DISTANCE_SENSOR's orientation MAV_SENSOR_ROTATION_PITCH_270 into pitch 270 (pointing down).
    """
    pitch = _num(d.orientation.pitch_deg) if d.orientation is not None else None
    if pitch is None or math.sin(math.radians(pitch)) > -0.99:
        return {}
    low, high, now = _num(d.minimum_distance_m), _num(d.maximum_distance_m), _num(d.current_distance_m)
    inside = now is not None and low is not None and high is not None and max(low, 0.0) < now < high
    return {"rangefinder_m": now if inside else None}


def from_battery(b: Any) -> Update:
    return {"battery_v": _num(b.voltage_v), "battery_pct": _num(b.remaining_percent)}


def from_gps_info(g: Any) -> Update:
    return {"gps_fix": g.fix_type.name, "satellites": int(g.num_satellites)}


def from_health(h: Any) -> Update:
    ok = (
        h.is_gyrometer_calibration_ok
        and h.is_accelerometer_calibration_ok
        and h.is_magnetometer_calibration_ok
        and h.is_local_position_ok
        and h.is_global_position_ok
        and h.is_home_position_ok
    )
    return {"health_ok": bool(ok)}


def from_unix_epoch_time(time_us: int) -> Update:
    """SYSTEM_TIME's UTC time as the offset from this computer's clock (0: the autopilot does not know it)."""
    return {"fc_clock_offset_ms": round(time_us / 1000 - time.time_ns() / 1e6)} if time_us > 0 else {}


STREAMS: dict[str, Callable[[Any], Update]] = {
    "position": from_position,
    "attitude_euler": from_attitude_euler,
    "velocity_ned": from_velocity_ned,
    "position_velocity_ned": from_position_velocity_ned,
    "distance_sensor": from_distance_sensor,
    "altitude": from_altitude,
    "battery": from_battery,
    "gps_info": from_gps_info,
    "health": from_health,
    "unix_epoch_time": from_unix_epoch_time,
    "armed": lambda armed: {"armed": bool(armed)},
    "in_air": lambda in_air: {"in_air": bool(in_air)},
}
"""``TelemetryAsync.subscribe_<name>`` -> converter into a partial update."""


async def set_rates(telemetry: TelemetryAsync, rates: dict[str, float] = RATES_HZ) -> dict[str, str]:
    """Ask the autopilot for each stream at its rate; returns {stream: failure} for those it refused.

    Refusals are logged, not raised: telemetry that keeps its default rate is still telemetry.
    """

    async def one(name: str, hz: float) -> tuple[str, str | None]:
        try:
            await getattr(telemetry, f"set_rate_{name}")(hz)
        except Exception as exc:  # noqa: BLE001 - any refusal is reported the same way
            return name, str(exc)
        return name, None

    results = await asyncio.gather(*(one(name, hz) for name, hz in rates.items()))
    failed = {name: err for name, err in results if err is not None}
    if failed:
        logger.info("telemetry rates not accepted by the autopilot: %s", failed)
    return failed


def message_readers(direct: MavlinkDirectAsync, system_id: int) -> dict[str, AsyncGenerator[Update, None]]:
    """Telemetry MAVSDK has no stream for, read from the autopilot's (``system_id``'s) raw messages (task name ->
    updates): ArduPilot's height above the terrain, the RC receiver's and the telemetry radio's signal."""
    return {"telemetry-terrain-report": terrain_reports(direct, system_id), **link_readers(direct, system_id)}


async def merged_updates(
    telemetry: TelemetryAsync, heartbeat_age_s: Callable[[], float], stop: asyncio.Event, subscriptions: Subscriptions,
    more: Sequence[Callable[[Callable[[Update], None]], asyncio.Task[None]]] = (),
) -> AsyncIterator[Update]:
    """Yield partial updates from every stream in :data:`STREAMS`, from each of ``more`` (started with the function
    that takes an update; returns its reader task) plus a heartbeat-age tick.

    Ends when ``stop`` is set. Subscriptions are cancelled when the consumer stops iterating, and by
    ``subscriptions.close()``.
    """
    queue: asyncio.Queue[Update | None] = asyncio.Queue()

    def pump(name: str, convert: Callable[[Any], Update]) -> asyncio.Task[None]:
        def put(value: Any) -> None:
            if update := convert(value):  # {}: nothing known yet
                queue.put_nowait(update)

        return subscriptions.read(getattr(telemetry, f"subscribe_{name}")(), put, f"telemetry-{name}")

    async def tick() -> None:
        while True:
            queue.put_nowait({"heartbeat_age_s": heartbeat_age_s()})
            await asyncio.sleep(HEARTBEAT_TICK_S)

    async def end_on_stop() -> None:
        await stop.wait()
        queue.put_nowait(None)

    tasks = [pump(n, c) for n, c in STREAMS.items()] + [start(queue.put_nowait) for start in more]
    tasks += [asyncio.create_task(tick(), name="telemetry-heartbeat"), asyncio.create_task(end_on_stop())]
    try:
        while (update := await queue.get()) is not None:
            yield update
    finally:
        for task in tasks:
            task.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
