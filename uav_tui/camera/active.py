"""The camera frames come from: the open source, its camera model, and opening another by URI.

The core owns one :class:`ActiveCamera`; commands open a new source through it and the core switches to it.
"""

from __future__ import annotations

import asyncio
import functools
from collections.abc import Callable, Coroutine
from enum import StrEnum
from typing import TYPE_CHECKING, Any

from controllers.base import PoseFeed
from sources import CameraSource, open_source, warm_up_source
from sources.base import KnowsCameraModel
from sources.pose import PoseTrack
from sources.uri import SourceUri
from uav_tui.camera import pose_feed
from uav_tui.errors import SourceError

if TYPE_CHECKING:
    from controllers.base import FlightController
    from controllers.replay_timeline import ReplayTimeline
    from uav_tui.config import CameraConfig
    from uav_tui.events import EventLog
    from uav_values.camera import CameraModel


class CameraKind(StrEnum):
    """What a camera URI asks of the platform besides opening it."""

    SIM = "sim"  # drawn from the vehicle's telemetry: it needs the vehicle's pose
    RUN = "run"  # a recorded run's frames: on the replay's clock when the vehicle is replayed too
    PLAIN = "plain"  # anything else: a camera, a file, a stream

    @classmethod
    def of(cls, uri: str) -> CameraKind:
        """The kind of ``uri``, from its scheme (:class:`~sources.uri.SourceUri`; SourceUriError without one)."""
        scheme = SourceUri.parse(uri).scheme
        return cls(scheme) if scheme in (cls.SIM, cls.RUN) else cls.PLAIN


class ActiveCamera:
    """Opens camera sources and holds the one frames come from now, with its camera model.

    Args:
        settings: the configured camera model (``[camera]``), for a source that states none of its own.
        events: where the chosen model and a missing pose are said.
        spawn: starts a task of the core's (``spawn(coro, name)``): the ``sim:`` camera's pose feed.
    """

    def __init__(self, settings: CameraConfig, events: EventLog,
                 spawn: Callable[[Coroutine[Any, Any, None], str], None]) -> None:
        self.settings = settings
        self.events = events
        self._spawn = spawn
        self.source: CameraSource | None = None
        self.model: CameraModel | None = None
        """The source's camera model (its own, or the configured one; None: none known); ``tmMgr.camera()``."""
        self.controller: FlightController | None = None
        """The vehicle whose telemetry a ``sim:`` camera draws from (set once it is connected)."""
        self.replay: ReplayTimeline | None = None
        """The replay's clock, for a ``run:`` source (``--fc replay:RUN``), else None."""
        self.pose_track: PoseTrack | None = None
        """The vehicle's pose from telemetry, once a ``sim:`` camera asked for it."""

    @staticmethod
    def warm_up(uri: str) -> asyncio.Future[None]:
        """Start the source's one-off preparation (the ``sim:`` camera's ground) in a thread, to overlap start-up."""
        return asyncio.get_running_loop().run_in_executor(None, warm_up_source, uri)

    async def open(self, uri: str) -> CameraSource:
        """Open the camera ``uri`` names (in a thread: opening can block), with the vehicle's pose for sim:."""
        context: dict[str, Any] = {}
        kind = CameraKind.of(uri)
        if kind is CameraKind.SIM:
            context["pose_provider"] = await self._vehicle_pose()
        if kind is CameraKind.RUN and self.replay is not None:
            context["timeline"] = self.replay
        return await asyncio.get_running_loop().run_in_executor(None, functools.partial(open_source, uri, **context))

    async def start(self, uri: str) -> CameraSource:
        """Open the run's camera and take frames from it; :meth:`close` closes it even when its model is refused."""
        self.source = await self.open(uri)
        self.model = self.model_of(self.source)
        return self.source

    def model_of(self, source: CameraSource) -> CameraModel | None:
        """``source``'s own model (``sim:``), else the configured one (``[camera]``), said in the event log.

        Raises CameraModelError when the model is for another frame size than the source gives.
        """
        width, height = source.get_frame_size()
        own = source.camera_model() if isinstance(source, KnowsCameraModel) else None
        model = own or self.settings.model(width, height)
        if model is not None and width and height:
            model.check_size(width, height)
        self.events.emit("info", "source", f"camera model: {model.describe()}" if model is not None else
                         "no camera model: set camera_calibration or camera_hfov ([camera]) to give processors one")
        return model

    def switch(self, source: CameraSource, model: CameraModel | None) -> CameraSource | None:
        """Frames come from ``source`` (with ``model``) from now on; returns the old source, still open."""
        old, self.source, self.model = self.source, source, model
        return old

    async def close(self) -> None:
        """Close the current source (in a thread: closing joins its capture thread)."""
        if self.source is not None:
            await asyncio.get_running_loop().run_in_executor(None, self.source.close)

    def newest_frame_age(self, clock: Callable[[], int]) -> float | None:
        """Seconds since the newest frame's capture on ``clock`` (monotonic ns), None before the first."""
        frame = self.source.buffer.peek() if self.source is not None else None
        return None if frame is None else (clock() - frame.t_mono_ns) / 1e9

    async def _vehicle_pose(self) -> PoseTrack:
        """The pose track fed from the controller's telemetry, started on first use (any MAVLink autopilot)."""
        if self.pose_track is None:
            if not isinstance(self.controller, PoseFeed):
                raise SourceError("the sim: camera draws the vehicle's view from its MAVLink telemetry: use it with "
                                  "--fc sim or a MAVLink connection string (e.g. udpin://0.0.0.0:14540)")
            self.pose_track = PoseTrack()
            self._spawn(pose_feed.feed(self.controller.pose_samples(), self.pose_track), "pose")
            if not await pose_feed.wait_first_pose(self.pose_track):
                self.events.emit("warning", "source", "no position/attitude telemetry yet: the sim: camera shows "
                                 "a hover at 10 m until it comes")
        return self.pose_track
