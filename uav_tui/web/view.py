"""What the side channels (the web page, the MAVLink camera component) use of a running core."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:
    from sources import CameraSource
    from uav_tui.events import EventLog
    from uav_tui.flight.commands import Command
    from uav_tui.flight.telemetry import TelemetryManager
    from uav_tui.flight.track_lock import TrackLock
    from uav_tui.relays.contract import HandledFrame
    from uav_tui.status import CoreState, CoreStatus
    from uav_values.camera import CameraModel


class FrameFeed(Protocol):
    """Processed frames, delivered on the loop to each listener added."""

    def add_frame_listener(self, listener: Callable[[HandledFrame], None]) -> None: ...

    def remove_frame_listener(self, listener: Callable[[HandledFrame], None]) -> None: ...


class ServedCore(FrameFeed, Protocol):
    """A running core as the side channels see it: its state, status, events, camera and commands."""

    @property
    def camera(self) -> CameraModel | None:
        """The camera model of the frames (geo-locates a box)."""
        ...

    @property
    def telemetry(self) -> TelemetryManager: ...

    @property
    def state(self) -> CoreState: ...

    @property
    def events(self) -> EventLog: ...

    @property
    def source(self) -> CameraSource | None: ...

    @property
    def lock(self) -> TrackLock:
        """The operator's lock on a track (a click inside a track's box locks it)."""
        ...

    def status(self) -> CoreStatus: ...

    async def execute(self, command: Command | str, origin: str = "script") -> str: ...
