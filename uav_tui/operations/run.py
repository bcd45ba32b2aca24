"""The run's own commands: a ``snapshot`` into the recording, a camera ``source`` switch, ``wait`` and ``quit``."""

from __future__ import annotations

import asyncio
from typing import TYPE_CHECKING

from uav_tui.errors import CommandError, SourceError, UavError
from uav_values.camera import CameraModelError

if TYPE_CHECKING:
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.hosting.host import ProcessorHost
    from uav_tui.operations.outcome import Handler
    from uav_tui.recording import Recorder


class RunCommands:
    """``snapshot``, ``source``, ``wait`` and ``quit``.

    Args:
        camera: the active camera ``source`` switches.
        worker: the processor's host, given the new camera's frames.
        recorder: the run's recorder (``snapshot``; it watches a new camera), None with ``--no-record``.
        quit_requested: set by ``quit``.
    """

    def __init__(self, camera: ActiveCamera, worker: ProcessorHost, recorder: Recorder | None,
                 quit_requested: asyncio.Event) -> None:
        self.camera = camera
        self.worker = worker
        self.recorder = recorder
        self.quit_requested = quit_requested

    def handlers(self) -> dict[str, Handler]:
        return {"snapshot": self._snapshot, "source": self._source, "wait": self._wait, "quit": self._quit}

    async def _snapshot(self, *, origin: str) -> str:
        if self.recorder is None:
            raise UavError("snapshot: recording is off (started with --no-record)")
        return self.recorder.snapshot()

    async def _source(self, uri: str, *, origin: str) -> str:
        active = self.camera
        new = await active.open(uri)
        try:
            camera = active.model_of(new)
        except (SourceError, CameraModelError):
            await asyncio.get_running_loop().run_in_executor(None, new.close)
            raise
        old = active.switch(new, camera)
        if self.recorder is not None:
            self.recorder.watch(new)  # before the worker attaches: each frame is copied before it is drawn on
        self.worker.attach(new.buffer, camera)
        if old is not None:
            await asyncio.get_running_loop().run_in_executor(None, old.close)
        width, height = new.get_frame_size()
        return f"camera switched to {uri} ({width}x{height})"

    async def _wait(self, seconds: float, *, origin: str) -> str:
        raise CommandError("wait is for --script files only", key="command")

    async def _quit(self, *, origin: str) -> str:
        self.quit_requested.set()
        return "quit requested"
