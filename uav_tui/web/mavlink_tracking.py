"""QGroundControl click-to-track: a MAVLink camera component that turns track commands into ``roi``.

A ground station sends MAV_CMD_CAMERA_TRACK_RECTANGLE or MAV_CMD_CAMERA_TRACK_POINT with normalized
image coordinates; they become the same ``roi X Y W H`` command (frame pixels) as a drag on the web
page, run through ``core.execute(..., origin="mavlink:SYS/COMP")``; a point inside a track's box on the newest frame
becomes ``lock ID`` instead (:func:`~uav_tui.web.roi.lock_or_roi`), and MAV_CMD_CAMERA_STOP_TRACKING releases the
lock. Every command gets a COMMAND_ACK, and CAMERA_TRACKING_IMAGE_STATUS reports what the processor tracks (its
``box`` on the newest processed frame, normalised; the locked track's while one is): active with the rectangle, idle
when it tracks nothing (or after MAV_CMD_CAMERA_STOP_TRACKING), error when its last frame raised; once after each
command, then once a second. Beside it, CAMERA_TRACKING_GEO_STATUS says where the box's centre is on the ground
(:mod:`uav_tui.flight.geolocate`, from the telemetry at the frame's capture): active with latitude, longitude,
altitude AMSL, ``h_acc`` (the 1-sigma uncertainty), ``v_acc`` and ``dist`` (straight-line range from the
vehicle); idle with latitude and longitude 0 and the rest NaN whenever there is no ground position (nothing
tracked, no camera model, no GPS, a box at the horizon), error as above. Velocity (north, east), its accuracy
and the heading are the target's from its positions on the frame clock (:mod:`uav_tui.flight.target_motion`), NaN
without enough of them; the down velocity is NaN (the ground is taken as flat). The component sends HEARTBEAT
(MAV_TYPE_CAMERA) and answers CAMERA_INFORMATION requests with the tracking capability flags, so a ground
station discovers it, and the video-stream requests for the ground-station videos (:mod:`uav_tui.web.video_streams`).

Endpoint (config ``camera_mavlink``): ``udpin:HOST:PORT`` listens and answers whoever spoke last;
``udpout:HOST:PORT`` (or ``udp:``) sends to a ground station / MAVLink router. All of it runs on the
event loop: a datagram endpoint, MAVLink 2 packing with pymavlink's generated dialect, no threads.

Anyone on the network can send to it, unauthenticated: every field is checked before use (a bad one is
DENIED, with a warning event), a message whose handling still raises is FAILED and reported
(:class:`HandlerFailures`), and commands beyond a rate (a ground station's clicks come far slower) or beyond
the queue are dropped and counted, the count said at most once a second.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict
from functools import partial
from typing import TYPE_CHECKING, Any

from pymavlink.dialects.v20 import common as mavlink

from uav_tui.errors import KNOWN_ERRORS, CommandError, ConfigError, UavError
from uav_tui.flight.commands import Command
from uav_tui.flight.geolocate import HEIGHT_SIGMAS, NO_BOX, OK, GeoFix, locate_row
from uav_tui.flight.target_motion import TargetMotion
from uav_tui.output.line_budget import LineBudget
from uav_tui.output.text import describe
from uav_tui.web.failures import HandlerFailures
from uav_tui.web.roi import lock_or_roi, point_to_roi, rect_to_roi
from uav_tui.web.video_streams import VideoStreams, address_toward
from uav_tui.web.view import ServedCore
from uav_values.box import PixelBox

if TYPE_CHECKING:
    from uav_tui.relays.contract import HandledFrame
    from uav_tui.web.ground_video import GroundVideo

logger = logging.getLogger(__name__)

STATUS_PERIOD_S = 1.0
"""HEARTBEAT, CAMERA_TRACKING_IMAGE_STATUS and CAMERA_TRACKING_GEO_STATUS are sent this often."""
NOT_LOCATED = GeoFix(NO_BOX)
"""The fix of a frame without a box."""

QUEUE_COMMANDS = 16
"""Commands waiting to be handled; more are dropped (and counted)."""

COMMANDS_PER_S = 5.0
COMMAND_BURST = 10
"""Commands taken at once, then a second; more are dropped (and counted): a flood costs the processor and the
event log no more than this."""

MAX_MESSAGE_ID = 2**24 - 1
"""MAVLink 2 message ids are 24 bits."""


def parse_endpoint(address: str) -> tuple[str, str, int]:
    """``udpin:0.0.0.0:14580`` -> ("udpin", "0.0.0.0", 14580); ``udp:`` means ``udpout:``."""
    scheme, _, rest = address.partition(":")
    host, _, port = rest.rpartition(":")
    scheme = "udpout" if scheme == "udp" else scheme
    if scheme not in ("udpin", "udpout") or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"camera_mavlink {address!r}: expected udpin:HOST:PORT (listen, e.g. "
                          "udpin:0.0.0.0:14580) or udpout:HOST:PORT (send to a ground station)", key="camera_mavlink")
    return scheme, host, int(port)


class _Writer:
    """The 'file' pymavlink's MAVLink object writes packed messages to: one datagram each."""

    def __init__(self, owner: CameraTracking) -> None:
        self.owner = owner

    def write(self, data: bytes) -> None:
        """udpin: to whoever spoke last; udpout: to the address the socket is connected to (asyncio refuses any
        other, and ``localhost`` is not the ``127.0.0.1`` it connected to)."""
        transport, peer = self.owner.transport, self.owner.peer
        if transport is not None and peer is not None:
            transport.sendto(bytes(data), peer if self.owner.scheme == "udpin" else None)


class _Datagrams(asyncio.DatagramProtocol):
    def __init__(self, owner: CameraTracking) -> None:
        self.owner = owner

    def datagram_received(self, data: bytes, addr: tuple[str, int]) -> None:
        self.owner.received(data, addr)


class CameraTracking:
    """The camera component for one running core.

    Args:
        core: the running core (:class:`~uav_tui.web.view.ServedCore`).
        address: ``udpin:HOST:PORT`` or ``udpout:HOST:PORT``.
        system_id: MAVLink system id (the vehicle's, so the ground station groups the camera with it).
        component_id: MAVLink component id (MAV_COMP_ID_CAMERA).
        videos: the ground-station videos it announces (:mod:`uav_tui.web.video_streams`).
    """

    def __init__(self, core: ServedCore, address: str, *, system_id: int = 1,
                 component_id: int = mavlink.MAV_COMP_ID_CAMERA, videos: Sequence[GroundVideo] = ()) -> None:
        self.core = core
        self.address = address
        self.scheme, self.host, self.port = parse_endpoint(address)
        self.mav = mavlink.MAVLink(_Writer(self), srcSystem=system_id, srcComponent=component_id)
        self.mav.robust_parsing = True
        self.streams = VideoStreams(self.mav, core, videos, self._local_address)
        """The ground-station videos this component announces (VIDEO_STREAM_INFORMATION), stream ids 1, 2, ..."""
        self.transport: asyncio.DatagramTransport | None = None
        self.peer: tuple[str, int] | None = None if self.scheme == "udpin" else (self.host, self.port)
        self.mode = mavlink.CAMERA_TRACKING_MODE_RECTANGLE
        """CAMERA_TRACKING_MODE_* of the last accepted track command."""
        self.reporting = True
        """False after MAV_CMD_CAMERA_STOP_TRACKING until the next track command: the status says idle."""
        self.tracked: tuple[PixelBox | None, tuple[int, int], bool] = (None, (0, 0), False)
        """The newest processed frame's box, its frame size and whether the processor raised on it."""
        self.located = NOT_LOCATED
        """Where that box is on the ground (seen with the telemetry at the frame's capture)."""
        self.motion = TargetMotion()
        """The box's positions on the ground, frame by frame: its velocity and heading."""
        self._commands: asyncio.Queue[Any] = asyncio.Queue(maxsize=QUEUE_COMMANDS)
        self._tasks: list[asyncio.Task[None]] = []
        self.failures = HandlerFailures(core.events, f"CameraTracking({address})")
        self.dropped = 0
        """Commands dropped: beyond the rate, or the queue full."""
        self._admit: LineBudget[Any] | None = None
        self._drops: LineBudget[int] | None = None

    async def start(self) -> None:
        loop = asyncio.get_running_loop()
        address = (self.host, self.port)
        local, remote = (address, None) if self.scheme == "udpin" else (None, address)
        try:
            self.transport, _ = await loop.create_datagram_endpoint(lambda: _Datagrams(self), local_addr=local,
                                                                    remote_addr=remote)
        except OSError as exc:
            raise UavError(f"camera_mavlink {self.address}: {exc.strerror}; is another program using the "
                           "port? pick another one") from exc
        self.core.add_frame_listener(self._on_frame)
        self._admit = LineBudget(self._enqueue, self._dropped, burst=COMMAND_BURST, per_s=COMMANDS_PER_S)
        self._drops = LineBudget(self._say_dropping, self._say_dropped, burst=1, per_s=1.0)
        self._tasks = [asyncio.create_task(self._handle_commands(), name="camera-commands"),
                       asyncio.create_task(self._report(), name="camera-status")]
        logger.info("CameraTracking(%s) started", self.address)

    async def stop(self) -> None:
        """Stop answering and close the socket. Idempotent."""
        self.core.remove_frame_listener(self._on_frame)
        for task in self._tasks:
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        self._tasks = []
        for budget in (self._admit, self._drops):
            if budget is not None:
                budget.close()
        self.failures.close()
        if self.transport is not None:
            self.transport.close()
            self.transport = None

    # -- receiving -------------------------------------------------------------------------------

    def _on_frame(self, result: HandledFrame) -> None:
        """Frame listener (on the loop): keep what the processor reported for the newest frame."""
        height, width = result.frame.image.shape[:2]
        box = result.outcome.box
        self.tracked = (box, (width, height), result.outcome.error is not None)
        if box is None:
            self.located = NOT_LOCATED
        else:  # where it was at the capture (~40 us)
            t_ns = result.frame.t_mono_ns
            seen = asdict(self.core.telemetry.at(t_ns)[0])
            self.located = locate_row(self.core.camera, box, seen, at_ns=t_ns)
            self.motion.add(t_ns, self.located)

    def received(self, data: bytes, addr: tuple[str, int]) -> None:
        """Datagram from the ground station (on the loop): queue the commands addressed to us."""
        if self.scheme == "udpin":
            self.peer = addr
        try:
            messages = self.mav.parse_buffer(data) or []
        except Exception as exc:  # noqa: BLE001 - pymavlink on bytes from anyone: a bug there costs one datagram
            self.failures.failed(f"a datagram from {describe(addr)}", exc)
            return
        for message in messages:
            if message.get_type() != "COMMAND_LONG":
                continue
            if message.target_system not in (0, self.mav.srcSystem) or \
                    message.target_component not in (0, self.mav.srcComponent):
                continue
            if self._admit is not None:
                self._admit.line(message)

    def _enqueue(self, message: Any) -> None:
        """A command within the rate: queued, or dropped (counted) when the queue is full."""
        if self._commands.full():
            self._dropped(1)
        else:
            self._commands.put_nowait(message)

    def _dropped(self, count: int) -> None:
        self.dropped += count
        if self._drops is not None:
            self._drops.lines(range(count))  # one item per command: the first said, the rest counted

    def _say_dropping(self, _: int) -> None:
        self.core.events.emit("warning", "web", f"camera component: dropping commands beyond {COMMANDS_PER_S:g} a "
                              f"second (or a full queue): is something flooding {self.address}? (counted once a "
                              "second)")

    def _say_dropped(self, count: int) -> None:
        self.core.events.emit("warning", "web", f"camera component: dropped {count} more command"
                              f"{'s' if count != 1 else ''} ({self.dropped} in all)")

    async def _handle_commands(self) -> None:
        while True:
            message = await self._commands.get()
            try:
                result, reply = await self._dispatch(message)
            except Exception as exc:  # noqa: BLE001 - a bug: this command fails, the next one is handled
                self.failures.failed(f"command {message.command} from {_origin(message)}", exc)
                result, reply = mavlink.MAV_RESULT_FAILED, None
            self._guarded(partial(self.mav.command_ack_send, message.command, result,
                                  target_system=message.get_srcSystem(), target_component=message.get_srcComponent()),
                          f"the ACK of command {message.command}")
            if reply is not None:  # requested messages follow their ACK
                self._guarded(reply, f"the reply to command {message.command}")

    def _guarded(self, send: Callable[[], None], what: str) -> None:
        try:
            send()
        except Exception as exc:  # noqa: BLE001 - a bug: reported, the component goes on
            self.failures.failed(what, exc)

    async def _dispatch(self, message: Any) -> tuple[int, Callable[[], None] | None]:
        """(MAV_RESULT, what to send after the ACK) for one COMMAND_LONG."""
        command, origin = message.command, _origin(message)
        params = (message.param1, message.param2, message.param3, message.param4)  # checked by rect/point_to_roi
        if command == mavlink.MAV_CMD_CAMERA_TRACK_RECTANGLE:
            return await self._select(mavlink.CAMERA_TRACKING_MODE_RECTANGLE, params, origin), self._send_status
        if command == mavlink.MAV_CMD_CAMERA_TRACK_POINT:
            return await self._select(mavlink.CAMERA_TRACKING_MODE_POINT, params, origin), self._send_status
        if command == mavlink.MAV_CMD_CAMERA_STOP_TRACKING:
            self.reporting = False
            self.core.events.emit("info", "command", "ground station stopped tracking (the processor keeps its "
                                  "target until the next selection)", origin)
            self.core.lock.release("the ground station stopped tracking", origin)
            return mavlink.MAV_RESULT_ACCEPTED, self._send_status
        requested = None
        if command == mavlink.MAV_CMD_REQUEST_MESSAGE:
            requested = _message_id(message.param1)
            if requested is None:
                self.core.events.emit("warning", "command", "camera command rejected: MAV_CMD_REQUEST_MESSAGE "
                                      f"param1 = {describe(message.param1)} is not a MAVLink message id", origin)
                return mavlink.MAV_RESULT_DENIED, None
        if command == mavlink.MAV_CMD_REQUEST_CAMERA_INFORMATION or \
                requested == mavlink.MAVLINK_MSG_ID_CAMERA_INFORMATION:
            return mavlink.MAV_RESULT_ACCEPTED, self._send_information
        if (answer := self.streams.answer(message, requested, origin)) is not None:
            return answer
        if requested == mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_IMAGE_STATUS:
            return mavlink.MAV_RESULT_ACCEPTED, self._send_image_status
        if requested == mavlink.MAVLINK_MSG_ID_CAMERA_TRACKING_GEO_STATUS:
            return mavlink.MAV_RESULT_ACCEPTED, self._send_geo_status
        return mavlink.MAV_RESULT_UNSUPPORTED, None

    async def _select(self, mode: int, params: tuple[float, float, float, float], origin: str) -> int:
        source = self.core.source
        size = source.get_frame_size() if source is not None else (0, 0)
        try:
            if mode == mavlink.CAMERA_TRACKING_MODE_RECTANGLE:
                command = Command("roi", rect_to_roi(*params, size))
            else:
                roi = point_to_roi(params[0], params[1], size, radius=params[2])
                command = lock_or_roi(roi, (params[0], params[1]), size, self.core.lock)
        except CommandError as exc:
            self.core.events.emit("warning", "command", f"camera track command rejected: {exc}", origin)
            return mavlink.MAV_RESULT_DENIED
        try:
            await self.core.execute(command, origin=origin)
        except KNOWN_ERRORS:  # logged as an event by the core
            return mavlink.MAV_RESULT_FAILED
        self.mode, self.reporting = mode, True
        self.motion.reset()  # another target
        return mavlink.MAV_RESULT_ACCEPTED

    # -- sending ---------------------------------------------------------------------------------

    async def _report(self) -> None:
        while True:
            self._guarded(self._send_heartbeat, "the heartbeat")
            self._guarded(self._send_status, "the tracking status")
            await asyncio.sleep(STATUS_PERIOD_S)

    def _send_heartbeat(self) -> None:
        self.mav.heartbeat_send(mavlink.MAV_TYPE_CAMERA, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, mavlink.MAV_STATE_ACTIVE)

    def _send_status(self) -> None:
        self._send_image_status()
        self._send_geo_status()

    def _reported(self) -> tuple[int, PixelBox | None]:
        """(CAMERA_TRACKING_STATUS_FLAGS_*, the box to report): the box only while the flag is active."""
        box, (width, height), failed = self.tracked
        if failed:
            return mavlink.CAMERA_TRACKING_STATUS_FLAGS_ERROR, None
        if box is None or not self.reporting or not width or not height:
            return mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE, None
        return mavlink.CAMERA_TRACKING_STATUS_FLAGS_ACTIVE, box

    def _send_image_status(self) -> None:
        flag, box = self._reported()
        if box is None:
            self.mav.camera_tracking_image_status_send(flag, mavlink.CAMERA_TRACKING_MODE_NONE, 0,
                                                       *([float("nan")] * 7))
            return
        _, (width, height), _ = self.tracked
        x, y, w, h = box  # normalised 0..1 (left/top 0), clipped: MAVLink has no room for off-image corners
        x0, x1 = (min(max(v / width, 0.0), 1.0) for v in (x, x + w))
        y0, y1 = (min(max(v / height, 0.0), 1.0) for v in (y, y + h))
        point = (x0 + x1) / 2, (y0 + y1) / 2, (x1 - x0) / 2
        self.mav.camera_tracking_image_status_send(
            flag, self.mode, mavlink.CAMERA_TRACKING_TARGET_DATA_IN_STATUS, *point, x0, y0, x1, y1)

    def _send_geo_status(self) -> None:
        (flag, box), fix, nan = self._reported(), self.located, float("nan")
        if box is None or fix.status != OK or fix.lat_deg is None or fix.lon_deg is None:
            idle = mavlink.CAMERA_TRACKING_STATUS_FLAGS_IDLE  # tracking, but nowhere on the ground
            self.mav.camera_tracking_geo_status_send(idle if box is not None else flag, 0, 0, *([nan] * 10))
            return
        v_acc = nan if fix.alt_m is None else HEIGHT_SIGMAS[fix.height_from]
        motion = self.motion.motion(time.monotonic_ns())
        self.mav.camera_tracking_geo_status_send(
            flag, round(fix.lat_deg * 1e7), round(fix.lon_deg * 1e7), _or_nan(fix.alt_m), _or_nan(fix.uncertainty_m),
            v_acc, motion.vel_n, motion.vel_e, nan, motion.vel_acc, _or_nan(fix.range_m), motion.heading_rad,
            motion.heading_acc_rad)

    def _send_information(self) -> None:
        size = self.core.source.get_frame_size() if self.core.source is not None else (0, 0)
        self.mav.camera_information_send(
            0, list(b"uav-tui".ljust(32, b"\0")), list(b"processed camera".ljust(32, b"\0")), 0, 0.0, 0.0, 0.0,
            size[0], size[1], 0,
            mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_POINT | mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_RECTANGLE
            | mavlink.CAMERA_CAP_FLAGS_HAS_TRACKING_GEO_STATUS
            | (mavlink.CAMERA_CAP_FLAGS_HAS_VIDEO_STREAM if self.streams.videos else 0), 0, b"")

    def _local_address(self) -> str:
        bound = self.transport.get_extra_info("sockname")[0] if self.transport is not None else self.host
        return address_toward(str(bound), self.peer)


def _or_nan(value: float | None) -> float:
    return float("nan") if value is None else value


def _origin(message: Any) -> str:
    return f"mavlink:{message.get_srcSystem()}/{message.get_srcComponent()}"


def _message_id(value: float) -> int | None:
    """MAV_CMD_REQUEST_MESSAGE's param1 as a message id, or None when it is not one (NaN, inf, 2.5, -3)."""
    if not (math.isfinite(value) and value == int(value) and 0 <= value <= MAX_MESSAGE_ID):
        return None
    return int(value)
