"""Who flies the vehicle on the processor's frames: ``autonomy`` on and off, the operator's ``lock`` on a track."""

from __future__ import annotations

from typing import TYPE_CHECKING

from processors.outputs import READERS
from uav_tui.errors import UavError
from uav_tui.flight.track_lock import LockState

if TYPE_CHECKING:
    from uav_tui.camera.active import ActiveCamera
    from uav_tui.flight.autonomy import AutonomyGate
    from uav_tui.flight.track_lock import TrackLock
    from uav_tui.hosting.host import ProcessorHost
    from uav_tui.operations.outcome import Handler


class AutonomyCommands:
    """``autonomy``, ``lock`` and ``unlock``.

    Args:
        gate: the autonomy gate ``autonomy`` switches.
        lock: the operator's lock on a track.
        worker: the processor's host (autonomy needs a processor that gives something to fly).
        camera: the active camera (a lock is on a track as its camera model sees it).
    """

    def __init__(self, gate: AutonomyGate, lock: TrackLock, worker: ProcessorHost, camera: ActiveCamera) -> None:
        self.gate = gate
        self.lock = lock
        self.worker = worker
        self.camera = camera

    def handlers(self) -> dict[str, Handler]:
        return {"autonomy": self._autonomy, "lock": self._lock, "unlock": self._unlock}

    async def _autonomy(self, switch: str, *, origin: str) -> str:
        gate = self.gate
        if switch == "on" or (switch == "toggle" and not gate.enabled):
            gate.check_can_enable()  # the vehicle's reasons first
            self._check_gives_outputs()
            gate.enable(origin)
        else:
            await gate.disable(origin)
        return ""

    def _check_gives_outputs(self) -> None:
        """Refuse autonomy for a processor that has nothing it could fly on (no vector nor any output of
        :data:`~processors.outputs.READERS`) while no track is locked: switched on, it would look armed for a flight
        that never comes."""
        info = self.worker.processor.info
        if self.lock.state is not LockState.OFF or {"getPreparedVector", *READERS} & info.capabilities:
            return
        close = "; ".join(info.warnings)  # a misspelt getPreparedVector, most likely
        raise UavError(f"autonomy refused: processor {info.name} has no getPreparedVector() (nor getLandingTarget() "
                       "or getGimbalPointing()), so it gives the vehicle nothing to fly (lock a track to fly after it)"
                       + (f"; {close}" if close else ""))

    async def _lock(self, track_id: int, *, origin: str) -> str:
        return self.lock.lock(track_id, self.camera.model, origin)

    async def _unlock(self, *, origin: str) -> str:
        return "" if self.lock.release("operator", origin) else "nothing was locked"
