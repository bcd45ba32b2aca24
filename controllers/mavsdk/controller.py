"""FlightController over MAVSDK 4 (the native binding): PX4 and ArduPilot on serial, UDP or TCP."""

from __future__ import annotations

import asyncio
import functools
import logging
import math
from collections.abc import AsyncIterator, Awaitable, Callable
from typing import Any, TypeVar

from mavsdk.asyncio import ComponentType, Configuration, Mavsdk, System
from mavsdk.asyncio.plugins.action import ActionAsync, OrbitYawBehavior
from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync
from mavsdk.asyncio.plugins.param import ParamAsync
from mavsdk.asyncio.plugins.telemetry import TelemetryAsync

from controllers.autopilots import Autopilot
from controllers.base import PoseSample
from controllers.connection import Connection, check_serial_device, parse_connection
from controllers.errors import ControllerError
from controllers.failsafe import STALE_MARGIN_S, FailsafeReport, ParamAccess, check_failsafe
from controllers.fence import FencePlan, ReadsFence
from controllers.landing_target_message import LandingTargetFix
from controllers.mavsdk import ardupilot
from controllers.mavsdk.attach import SETUP_TIMEOUT_S, ask_for_telemetry, reach_autopilot
from controllers.mavsdk.calls import AbandoningExecutor, Subscriptions, bounded, release, use_abandoning_executor
from controllers.mavsdk.geofence import download_plan
from controllers.mavsdk.gimbal import MavsdkGimbal
from controllers.mavsdk.landing import MavsdkLanding
from controllers.mavsdk.link import LinkMonitor
from controllers.mavsdk.log import route_mavsdk_log
from controllers.mavsdk.offboard import MavsdkOffboard
from controllers.mavsdk.pose import POSE_RATE_HZ, pose_samples, request_pose_rate
from controllers.mavsdk.telemetry import merged_updates, message_readers
from controllers.mavsdk.vector_stream import DEFAULT_RATE_HZ, VectorStream
from controllers.precland_requirements import LANDING_MODES
from controllers.vector_end import VectorEnd

logger = logging.getLogger(__name__)

T = TypeVar("T")

COMMAND_TIMEOUT_S = 10.0
"""Upper bound on any one command; MAVSDK's own retries end well before it."""

CLOSE_HOLD_TIMEOUT_S = 2.0
"""close() during a vector: how long it tries to put the vehicle in hold before letting go."""

PARAM_TIMEOUT_S = 5.0
"""Upper bound on one parameter read or write (MAVSDK retries PARAM_REQUEST_READ / PARAM_SET itself)."""

RELEASE_TIMEOUT_S = 2.0
"""close(): how long MAVSDK may take to release its connections before it is abandoned."""


class MavsdkController(ReadsFence):
    """A flight controller reached through MAVSDK 4.

    Example::

        fc = MavsdkController()
        await fc.connect("udpin://0.0.0.0:14540")
        await fc.arm()
        await fc.takeoff(5.0)
        await fc.set_fly_vector(0.5, 0.0, 2.0)

    Args:
        vector_rate_hz: setpoint rate while a vector runs (>= 10).
        command_timeout_s: upper bound on each command.
    """

    def __init__(self, *, vector_rate_hz: float = DEFAULT_RATE_HZ,
                 command_timeout_s: float = COMMAND_TIMEOUT_S) -> None:
        self.description = "MAVSDK (not connected)"
        self.autopilot = Autopilot.UNKNOWN
        """PX4, ArduPilot or unknown, from the heartbeat's autopilot field."""
        self.connection: Connection | None = None
        self._command_timeout_s = command_timeout_s
        self._mavsdk: Mavsdk | None = None
        self._system: System | None = None
        self._sysid = 1
        self._action: ActionAsync
        self._telemetry: TelemetryAsync
        self._param: ParamAsync
        self._direct: MavlinkDirectAsync
        self._link: LinkMonitor | None = None
        self._executor: AbandoningExecutor | None = None
        self._stop = asyncio.Event()
        self._subscriptions = Subscriptions()
        self._closed = False
        self._offboard = MavsdkOffboard(self, self._command)
        """Velocity control: the setpoints, and the switches into and out of the velocity-control mode."""
        self._vectors = VectorStream(self._offboard, rate_hz=vector_rate_hz, name="MavsdkController")
        self._landing: MavsdkLanding | None = None
        """LANDING_TARGET on the autopilot's clock, and the precision landing (once connected)."""
        self._gimbal: MavsdkGimbal | None = None
        """The vehicle's gimbal, when it has one (once connected)."""

    # ---- connection ------------------------------------------------------------------------------

    async def connect(self, system_address: str, heartbeat_timeout: float = 10.0) -> None:
        """Connect, wait for the autopilot's heartbeat, detect PX4/ArduPilot, ask for telemetry.

        Raises:
            ConnectError: bad string, missing/busy/forbidden serial device, port in use, or no
                heartbeat within ``heartbeat_timeout`` seconds.
        """
        if self._mavsdk is not None or self._closed:
            raise RuntimeError("MavsdkController.connect() can be called once, on a new controller")
        conn = parse_connection(system_address)
        if conn.translated:
            logger.info("connection %r passed to MAVSDK as %s", conn.given, conn.url)
        if conn.is_serial:
            await asyncio.to_thread(check_serial_device, conn.device or "")
        route_mavsdk_log()
        self._executor = use_abandoning_executor()
        self.connection = conn
        self._mavsdk = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
        try:
            await self._attach(conn, heartbeat_timeout)
        except BaseException:
            await self.close()
            raise
        self.description = f"{self.autopilot.label} via {conn.url}"
        logger.info("MavsdkController connected: %s (system %d)", self.description, self._sysid)

    async def _attach(self, conn: Connection, heartbeat_timeout: float) -> None:
        assert self._mavsdk is not None
        reached = await reach_autopilot(self._mavsdk, conn, heartbeat_timeout)
        self._system, self._sysid, self.autopilot = reached.system, reached.sysid, reached.autopilot
        self._action, self._telemetry, self._param, self._direct = (reached.action, reached.telemetry, reached.param,
                                                                    reached.direct)
        self._link = LinkMonitor(self._direct, self._telemetry, self._sysid, self._subscriptions)
        self._link.start()
        self._landing = MavsdkLanding(reached, self._command)
        self._offboard.attach(reached, self._subscriptions)
        self._gimbal = MavsdkGimbal(reached.system, self._command)
        self._gimbal.watch_list(self._subscriptions)
        self._subscriptions.read(self._direct.subscribe_message("ATTITUDE"), self._landing.on_attitude,
                                 "mavsdk-boot-clock")
        await ask_for_telemetry(reached, self.heartbeat_age_s)

    @property
    def own_modes(self) -> frozenset[str]:
        """Flight modes (MAVSDK's names) this controller's vectors and holds leave the vehicle in.

        ArduCopter's hold is GUIDED (OFFBOARD), never LOITER or BRAKE (HOLD): a vehicle in HOLD there
        was put there by a pilot or a failsafe.
        """
        return frozenset({"OFFBOARD"}) if self.autopilot is Autopilot.ARDUPILOT else frozenset({"HOLD", "OFFBOARD"})

    def heartbeat_age_s(self) -> float:
        """Seconds since the last heartbeat from the autopilot (inf before the first)."""
        return self._link.heartbeat_age_s() if self._link is not None else math.inf

    def flight_mode_since(self, t_mono: float) -> str | None:
        """The flight mode last reported, if it arrived after ``t_mono`` (see :class:`LinkMonitor`)."""
        return self._link.flight_mode_since(t_mono) if self._link is not None else None

    async def wait_ready(self, timeout_s: float = 30.0) -> bool:
        """Wait until the autopilot reports it could arm; False after ``timeout_s``.

        PX4 needs ~5 s after boot, the simulator ~1 s (ArduCopter's flags look good before its EKF
        allows GUIDED arming, ~40 s after boot).
        """
        return await self._link.wait_ready(timeout_s) if self._link is not None else False

    async def close(self) -> None:
        """Stop a running vector (zero, hold: best effort), stop streams, release MAVSDK. Idempotent."""
        if self._closed:
            return
        if self._vectors.active or self._vectors.engaged:
            await _best_effort("put the vehicle in hold", self._vectors.stop_and_hold)
        await _best_effort("release the gimbal", self.release_gimbal)
        self._closed = True
        self._stop.set()
        await self._vectors.cancel()
        await self._subscriptions.close()  # the link monitor's too; every unsubscribe done before MAVSDK is destroyed
        mavsdk, self._mavsdk = self._mavsdk, None
        if mavsdk is not None and self._executor is not None:
            await release(mavsdk, self._executor, RELEASE_TIMEOUT_S)
        logger.info("MavsdkController closed (%s)", self.description)

    @property
    def unfinished_calls(self) -> list[str]:
        """MAVSDK calls whose threads are still blocked (abandoned: they do not keep the process alive)."""
        return self._executor.running if self._executor is not None else []

    # ---- failsafe parameters ---------------------------------------------------------------------

    async def check_failsafe(self, max_t: float, *, tune: bool) -> FailsafeReport:
        """Check (and with ``tune`` set: set those that break a rule) the autopilot's offboard-loss parameters, see
        :mod:`controllers.failsafe`; ``max_t``: the longest vector (a dead platform's last lasts ``max_t`` + 0.5 s)."""
        return await check_failsafe(self.autopilot, self._params(), max_t + STALE_MARGIN_S, tune=tune,
                                    rc_receiver=self._link.rc_receiver_present if self._link is not None else None)

    def _params(self) -> ParamAccess:
        return ParamAccess(self._param, lambda name, call: bounded(name, call, PARAM_TIMEOUT_S, self.heartbeat_age_s))

    async def _fence_plan(self) -> FencePlan:
        assert self._system is not None  # read after connect()
        return await self._command("download_geofence", functools.partial(download_plan, self._system))

    # ---- commands --------------------------------------------------------------------------------

    async def _command(self, name: str, call: Callable[[], Awaitable[T]]) -> T:
        """Run one MAVSDK call bounded in time, with its errors translated at one boundary."""
        if self._system is None or self._closed:
            raise ControllerError(f"{name}: not connected (call connect() first)")
        return await bounded(name, call, self._command_timeout_s, self.heartbeat_age_s)

    async def arm(self) -> None:
        await self._offboard.guided("arm")
        await self._command("arm", self._action.arm)

    async def disarm(self) -> None:
        await self._vectors.stop_and_hold()
        await self._command("disarm", self._action.disarm)

    async def takeoff(self, altitude_m: float | None = None) -> None:
        await self._vectors.stop_and_hold()
        if self.autopilot is Autopilot.ARDUPILOT:
            await self._offboard.guided("takeoff")
            alt = altitude_m if altitude_m is not None else ardupilot.DEFAULT_TAKEOFF_ALT_M
            await self._command("takeoff", lambda: ardupilot.takeoff(self._direct, self._sysid, alt))
            return
        if altitude_m is not None:
            await self._command("takeoff", lambda: self._action.set_takeoff_altitude(float(altitude_m)))
        await self._command("takeoff", self._action.takeoff)

    async def land(self) -> None:
        await self._vectors.stop_and_hold()
        await self._command("land", self._action.land)

    async def return_to_home(self) -> None:
        await self._vectors.stop_and_hold()
        await self._command("return_to_home", self._action.return_to_launch)

    async def hold(self) -> None:
        if self._vectors.active or self._vectors.engaged:
            await self._vectors.stop_and_hold()  # zero first, then the holding mode
        else:
            await self._offboard.stop_offboard()

    async def do_orbit(self, radius_m: float, velocity_ms: float) -> None:
        await self._vectors.stop_and_hold()
        if self.autopilot is Autopilot.ARDUPILOT:
            await self._command(
                "do_orbit",
                lambda: ardupilot.start_circle(self._direct, self._param, self._sysid, radius_m, velocity_ms),
            )
            return
        # Centre: the current position, given explicitly, because MAVSDK sends a NaN latitude as
        # COMMAND_INT x = INT32_MIN (not INT32_MAX, "current position"). Altitude NaN: keep the current one
        # (MAVSDK labels z GLOBAL_RELATIVE_ALT while the API takes AMSL; NaN avoids the ambiguity).
        here = await self._command("do_orbit", self._telemetry.position)
        facing = OrbitYawBehavior.HOLD_FRONT_TO_CIRCLE_CENTER
        await self._command("do_orbit", lambda: self._action.do_orbit(radius_m, velocity_ms, facing, here.latitude_deg,
                                                                      here.longitude_deg, math.nan))

    async def set_fly_vector(self, vx: float, vy: float, t: float, *, yield_to_others: bool = False) -> None:
        """Fly body-frame (vx forward, vy right) m/s for t s, yaw and height held.

        ``yield_to_others`` (autonomy's vectors, not an operator's command): refused when the vehicle reports, right
        before the switch to offboard, a mode that is not the platform's own (a pilot switched as it was sent).

        Returns once the first setpoint is out and offboard is engaged; then zero + hold at the end. A new vector
        replaces a running one without leaving offboard. The height is held by :mod:`~controllers.mavsdk.height_hold`.

        Raises:
            ValueError: non-finite speeds or t <= 0 (the autonomy gate rejects those first).
            ControllerError: offboard refused, link lost.
        """
        if not all(math.isfinite(v) for v in (vx, vy, t)) or t <= 0:
            raise ValueError(f"set_fly_vector({vx}, {vy}, {t}): speeds must be finite and t > 0")
        if self._system is None or self._closed:
            raise ControllerError("set_fly_vector: not connected (call connect() first)")
        await self._vectors.start(float(vx), float(vy), float(t), yield_to_others=yield_to_others)

    @property
    def vector_active(self) -> bool:
        """True while a vector's setpoints are being streamed, and until its end (zero, then the hold) is out."""
        return self._vectors.active

    @property
    def last_vector_end(self) -> VectorEnd:
        """How the last vector ended (see :class:`~controllers.vector_end.VectorEnd`)."""
        return self._vectors.last_end

    # ---- landing target -------------------------------------------------------------------------

    async def send_landing_target(self, fix: LandingTargetFix) -> dict[str, Any]:
        """LANDING_TARGET for ``fix``'s target; the fields sent (:meth:`.MavsdkLanding.send`)."""
        return await self._connected_landing("landing_target").send(fix)

    async def precision_land(self) -> str:
        """Land on the target sent last; what was done (:meth:`.MavsdkLanding.precision_land`)."""
        return await self._connected_landing("precland").precision_land(self.land, self._vectors.stop_and_hold)

    @property
    def landing_modes(self) -> frozenset[str]:
        """The flight modes the vehicle reports while it lands precisely (:data:`LANDING_MODES`)."""
        return LANDING_MODES.get(self.autopilot, frozenset({"LAND"}))

    def _connected_landing(self, name: str) -> MavsdkLanding:
        if self._landing is None or self._closed:
            raise ControllerError(f"{name}: not connected (call connect() first)")
        return self._landing

    # ---- gimbal (controllers.mavsdk.gimbal) -------------------------------------------------------

    async def point_gimbal(self, mode: str, pitch: float, yaw: float) -> None:
        """Take control of the gimbal if not held, then stream the setpoint (:meth:`MavsdkGimbal.point`)."""
        if self._gimbal is None or self._closed:
            raise ControllerError("gimbal: not connected (call connect() first)")
        await self._gimbal.point(mode, pitch, yaw)

    async def release_gimbal(self) -> None:
        """Stop the gimbal and release control if held (:meth:`MavsdkGimbal.release`)."""
        if self._gimbal is not None:
            await self._gimbal.release()

    @property
    def gimbal_controlled(self) -> bool:
        return self._gimbal is not None and self._gimbal.controlled

    # ---- telemetry -------------------------------------------------------------------------------

    async def telemetry(self) -> AsyncIterator[dict[str, Any]]:
        """Partial telemetry updates keyed by Telemetry field names; ends when the controller closes."""
        if self._system is None:
            raise ControllerError("telemetry: not connected (call connect() first)")
        gimbal, link = self._gimbal, self._link
        more: list[Callable[[Callable[[dict[str, Any]], None]], asyncio.Task[None]]] = []
        if link is not None:
            more.append(link.follow_modes)  # MAVSDK's names, and HEARTBEAT's where MAVSDK has none
        if gimbal is not None:
            more.append(lambda put: gimbal.read_attitude(self._subscriptions, put))
        more += [functools.partial(self._subscriptions.read, reader, name=name)
                 for name, reader in message_readers(self._direct, self._sysid).items()]
        async for update in merged_updates(self._telemetry, self.heartbeat_age_s, self._stop, self._subscriptions,
                                           more):
            yield update

    async def pose_samples(self, rate_hz: float = POSE_RATE_HZ) -> AsyncIterator[PoseSample]:
        """Position and attitude samples, each stamped with when it was valid (see :mod:`controllers.mavsdk.pose`).

        Asks the autopilot for LOCAL_POSITION_NED and ATTITUDE at ``rate_hz`` first; ends when the
        controller closes. What the ``sim:`` camera is drawn from, for every autopilot.
        """
        if self._system is None:
            raise ControllerError("pose_samples: not connected (call connect() first)")
        await request_pose_rate(self._direct, self._sysid, rate_hz, SETUP_TIMEOUT_S)
        async for sample in pose_samples(self._direct, self._sysid, self._stop, self._subscriptions):
            yield sample


async def _best_effort(what: str, call: Callable[[], Awaitable[object]]) -> None:
    """Run ``call`` while closing, bounded; what goes wrong is logged, and closing goes on."""
    try:
        async with asyncio.timeout(CLOSE_HOLD_TIMEOUT_S):
            await call()
    except (ControllerError, TimeoutError) as exc:
        logger.error("MavsdkController: could not %s while closing: %s", what,
                     str(exc) or f"no answer within {CLOSE_HOLD_TIMEOUT_S:g} s")
