"""TelemetryManager: the newest telemetry (and a few seconds of it), readable from any thread.

Processors do not see it directly: their ``self.tmMgr`` is a :class:`processors.frame_telemetry.FrameTelemetry`
whose snapshot the host fills from :meth:`TelemetryManager.at` (the telemetry at the frame's capture) and whose
saves it stores through :meth:`TelemetryManager.save`.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from controllers.base import RECEIVE_STAMPS, TELEMETRY_FIELDS, FlightController, Telemetry
from uav_tui.errors import ControllerError
from uav_tui.flight.telemetry_sanity import problems

logger = logging.getLogger(__name__)

Listener = Callable[[Telemetry], None]
Saver = Callable[[Any, dict[str, Any]], None]

_FIELDS = frozenset(TELEMETRY_FIELDS)
_UPDATABLE = _FIELDS - {"t_mono_ns", "t_wall_ns", "heartbeat_age_s"}
"""Fields a controller update may set; receive stamps and heartbeat age are set here (a replayed
update brings its recorded receive stamps)."""
HISTORY = 1024
"""Updates kept for :meth:`TelemetryManager.at` (several seconds: MAVSDK sends a few hundred a second)."""


class TelemetryManager:
    """Keeps the newest :class:`Telemetry` from a flight controller's update stream.

    ``run()`` runs on the event loop; ``snapshot()``, ``link_alive()`` and ``save()`` may be called
    from any thread (processors call them from the processor thread).

    Args:
        controller: where telemetry comes from; None (``--fc none``) gives an all-None Telemetry.
    """

    def __init__(self, controller: FlightController | None) -> None:
        self.controller = controller
        self.saver: Saver | None = None
        """Set by the platform: ``saver(frame, extra)`` stores a frame with the telemetry of its capture."""
        self.updates = 0
        """Updates received from the controller."""
        self.saves_dropped = 0
        """``save()`` calls made while no saver was set (recording off)."""
        self.listener_errors = 0
        """Exceptions raised by listeners (each listener's first one is logged)."""
        self.refused: dict[str, str] = {}
        """Field -> why its last impossible value was made None (:mod:`.telemetry_sanity`; each field logged once)."""
        self.values_refused = 0
        self._lock = threading.Lock()
        self._latest = Telemetry()
        self._history: deque[Telemetry] = deque(maxlen=HISTORY)
        self._listeners: list[Listener] = []
        self._warned: set[str] = set()

    async def run(self) -> None:
        """Consume the controller's telemetry until it ends (the controller closed); no-op without one."""
        if self.controller is None:
            return
        try:
            async for update in self.controller.telemetry():
                self.apply(update)
        except ControllerError as exc:
            logger.error("TelemetryManager: telemetry stream ended: %s", exc)

    def apply(self, update: dict[str, Any]) -> Telemetry:
        """Merge one partial update, stamp it with receive times, and tell the listeners.

        A value that cannot be true (:func:`~uav_tui.flight.telemetry_sanity.problems`) is merged as None: the last
        one it had is not kept either, and :attr:`refused` says why.

        Returns:
            The new newest Telemetry.
        """
        known = {k: v for k, v in update.items() if k in _UPDATABLE}
        for name, why in problems(known):
            known[name] = None
            self.values_refused += 1
            if self.refused.get(name) is None:
                logger.warning("TelemetryManager: %s: taken as not known", why)
            self.refused[name] = why
        t_mono_ns = update.get("t_mono_ns") or time.monotonic_ns()
        known |= {stamp: t_mono_ns for name, stamp in RECEIVE_STAMPS.items() if name in known and stamp not in known}
        unknown = set(update) - _FIELDS  # a heartbeat_age_s tick is known: it refreshes the age
        if unknown:
            self._warn_once("unknown", "TelemetryManager: ignoring unknown fields %s", sorted(unknown))
        with self._lock:
            self._latest = dataclasses.replace(
                self._latest,
                **known,
                t_mono_ns=t_mono_ns,
                t_wall_ns=update.get("t_wall_ns") or time.time_ns(),
                heartbeat_age_s=self._heartbeat_age(),
            )
            latest = self._latest
            self._history.append(latest)
        self.updates += 1
        for listener in list(self._listeners):
            try:
                listener(latest)
            except Exception:
                self.listener_errors += 1
                if f"listener-{id(listener)}" not in self._warned:
                    self._warned.add(f"listener-{id(listener)}")
                    logger.exception("TelemetryManager: listener %r failed (logged once)", listener)
        return latest

    def snapshot(self) -> Telemetry:
        """The newest values, with the heartbeat age as of now. Thread-safe."""
        latest, heartbeat_age = self.newest()
        return dataclasses.replace(latest, heartbeat_age_s=heartbeat_age)

    def newest(self) -> tuple[Telemetry, float | None]:
        """The newest update as stored (the same object until the next update) and the heartbeat age as of now.

        For readers that convert the telemetry once per update instead of once per frame. Thread-safe.
        """
        with self._lock:
            latest = self._latest
        return latest, self._heartbeat_age()

    def at(self, t_mono_ns: int) -> tuple[Telemetry, float | None]:
        """The telemetry as it was at ``t_mono_ns`` (a frame's capture) and the heartbeat age as of now. Thread-safe.

        That is the newest update received at or before ``t_mono_ns`` (its receive stamp; a replay's are the
        recorded ones), an all-None Telemetry when none was, or the oldest kept when the instant is older than
        :data:`HISTORY` updates.
        """
        with self._lock:
            found = next((item for item in reversed(self._history) if item.t_mono_ns <= t_mono_ns), None)
            if found is None:
                full = len(self._history) == self._history.maxlen
                found = self._history[0] if full else Telemetry()
        return found, self._heartbeat_age()

    def add_listener(self, callback: Listener) -> None:
        """Call ``callback(telemetry)`` on the event loop for every update (the recorder writes a row)."""
        self._listeners.append(callback)

    def link_alive(self, max_age_s: float = 1.5) -> bool:
        """True when the autopilot's last heartbeat is younger than ``max_age_s``."""
        age = self._heartbeat_age()
        return age is not None and age < max_age_s

    def save(self, frame: Any, **extra: Any) -> None:
        """Store ``frame`` with the telemetry of its capture and ``extra`` columns (one call, any thread)."""
        saver = self.saver
        if saver is None:
            self.saves_dropped += 1
            self._warn_once("saver", "TelemetryManager.save(): recording is off, frames are not stored")
            return
        saver(frame, extra)

    def _heartbeat_age(self) -> float | None:
        if self.controller is None:
            return None
        age = self.controller.heartbeat_age_s()
        return age if math.isfinite(age) else None

    def _warn_once(self, key: str, message: str, *args: Any) -> None:
        if key not in self._warned:
            self._warned.add(key)
            logger.warning(message, *args)
