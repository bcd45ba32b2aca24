"""The flight-controller contract; the telemetry value types it produces live in :mod:`uav_values.telemetry`."""

from __future__ import annotations

from collections.abc import AsyncIterator
from pathlib import Path
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

from controllers.vector_end import VectorEnd as VectorEnd
from controllers.vector_end import VectorEndKind as VectorEndKind
from uav_values.telemetry import RECEIVE_STAMPS as RECEIVE_STAMPS
from uav_values.telemetry import TELEMETRY_FIELDS as TELEMETRY_FIELDS
from uav_values.telemetry import PoseSample as PoseSample
from uav_values.telemetry import Telemetry as Telemetry

if TYPE_CHECKING:
    from controllers.failsafe import FailsafeReport
    from controllers.fence import FenceReport
    from controllers.landing_target_message import LandingTargetFix
    from controllers.replay_timeline import ReplayTimeline


@runtime_checkable
class FlightController(Protocol):
    """What the platform needs from a flight controller.

    Every command either completes or raises a :class:`uav_tui.errors.ControllerError` carrying the
    autopilot's answer; none is a silent no-op.

    ``set_fly_vector`` returns as soon as the vector is running; the controller streams the
    body-frame velocity setpoint at >= 10 Hz for ``t`` seconds, then sends zero and puts the vehicle
    in a holding mode itself. A new vector replaces the running one.

    Optional capabilities are the small Protocols below (:class:`FailsafeCheck`, :class:`PoseFeed`,
    :class:`OwnModes`, :class:`LandingTargets`, :class:`GimbalControl`, :class:`PrecisionLanding`,
    :class:`BlockingCalls`, :class:`SimulatorOwner`, :class:`RecordedVehicle`); the platform asks
    ``isinstance(controller, PoseFeed)`` and uses what the answer allows.
    """

    description: str
    """Human-readable: autopilot kind and connection string."""

    async def connect(self, system_address: str) -> None: ...
    async def close(self) -> None: ...
    async def arm(self) -> None: ...
    async def disarm(self) -> None: ...
    async def takeoff(self, altitude_m: float | None = None) -> None: ...
    async def land(self) -> None: ...
    async def set_fly_vector(self, vx: float, vy: float, t: float, *, yield_to_others: bool = False) -> None: ...
    async def do_orbit(self, radius_m: float, velocity_ms: float) -> None: ...
    async def return_to_home(self) -> None: ...
    async def hold(self) -> None: ...

    @property
    def vector_active(self) -> bool:
        """True while a vector's setpoints are being streamed, and until its end (zero, then the hold) is out."""
        ...

    @property
    def last_vector_end(self) -> VectorEnd:
        """How the last vector ended (its ``kind``); ``str()`` reads ``completed``, ``stopped``,
        ``vehicle left offboard (MODE)`` or ``failed: ...``."""
        ...

    def heartbeat_age_s(self) -> float:
        """Seconds since the last heartbeat from the autopilot (inf before the first)."""
        ...

    def telemetry(self) -> AsyncIterator[dict[str, Any]]:
        """Partial telemetry updates keyed by :class:`Telemetry` field names, as they arrive."""
        ...


@runtime_checkable
class FailsafeCheck(Protocol):
    """A controller that can read (and set) the autopilot's offboard-loss failsafe (MAVLink autopilots)."""

    async def check_failsafe(self, max_t: float, *, tune: bool) -> FailsafeReport:
        """Check the failsafe against vectors of up to ``max_t`` s; with ``tune``, set what allows longer."""
        ...


@runtime_checkable
class FenceCheck(Protocol):
    """A controller that can read whether the autopilot's own geofence is set up (MAVLink autopilots)."""

    async def check_fence(self) -> FenceReport: ...


@runtime_checkable
class PoseFeed(Protocol):
    """A controller that streams the vehicle's pose, which the ``sim:`` camera is drawn from."""

    def pose_samples(self) -> AsyncIterator[PoseSample]:
        """Timestamped position and attitude samples (:class:`PoseSample`), as they arrive."""
        ...


@runtime_checkable
class OwnModes(Protocol):
    """A controller that says which flight modes its own vectors and holds leave the vehicle in.

    Without it: HOLD and OFFBOARD. Any other mode is a pilot's, a mission's or a failsafe's, which
    autonomy and the hold at exit leave alone.
    """

    @property
    def own_modes(self) -> frozenset[str]: ...


@runtime_checkable
class LandingTargets(Protocol):
    """A controller that sends LANDING_TARGET (precision landing) for a target seen in a frame."""

    async def send_landing_target(self, fix: LandingTargetFix) -> dict[str, Any]:
        """Send it converted for the autopilot and stamped with the frame's capture time on its clock; returns
        what was sent."""
        ...


@runtime_checkable
class GimbalControl(Protocol):
    """A controller that points a gimbal (MAVLink gimbal protocol v2)."""

    async def point_gimbal(self, mode: str, pitch: float, yaw: float) -> None:
        """Take control of the gimbal if not held yet, then send the setpoint: ``mode`` ``rate`` (deg/s) or ``angle``
        (degrees, yaw from the nose), pitch positive up. Raises ControllerError (NotSupported: no gimbal)."""
        ...

    async def release_gimbal(self) -> None:
        """Stop the gimbal and release control; nothing when control is not held."""
        ...

    @property
    def gimbal_controlled(self) -> bool:
        """Control of the gimbal is held."""
        ...


@runtime_checkable
class PrecisionLanding(Protocol):
    """A controller that starts a precision landing on the LANDING_TARGETs it is sent."""

    async def precision_land(self) -> str:
        """Set what the autopilot needs and land on the target; returns what was done, raises ControllerError
        saying why not."""
        ...

    @property
    def landing_modes(self) -> frozenset[str]:
        """The flight modes (:mod:`controllers.flight_modes` names) the vehicle reports while it lands on the
        target."""
        ...


@runtime_checkable
class BlockingCalls(Protocol):
    """A controller whose calls can stay blocked in a thread after it is closed (MAVSDK's)."""

    @property
    def unfinished_calls(self) -> list[str]:
        """The calls still blocked (abandoned: they do not keep the process alive)."""
        ...


class Simulator(Protocol):
    """A simulator process a controller owns."""

    def exit_status(self) -> str | None:
        """How the process ended by itself (``"killed by SIGKILL"``), else None (running, or stopped on request)."""
        ...


@runtime_checkable
class SimulatorOwner(Protocol):
    """A controller that started the simulated vehicle it flies (``--fc sim``)."""

    sim: Simulator


@runtime_checkable
class RecordedVehicle(Protocol):
    """A controller that replays a recorded run's vehicle (``--fc replay:RUN``): nothing is ever sent."""

    run_dir: Path
    """The recorded run's folder."""
    timeline: ReplayTimeline
    """Where the replay is on the recorded clock; shared with the ``run:`` camera of the same run."""
