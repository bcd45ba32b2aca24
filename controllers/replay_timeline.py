"""Where a replay is on the recorded clock, shared by the replayed vehicle, the ``run:`` camera and the platform.

Times are the recorded monotonic nanoseconds of the run being replayed. Two ways to move:

* **paced** (``speed`` a number): recorded time runs ``speed`` times as fast as this computer's clock,
  from the instant the replay starts; frames and telemetry are served when their time comes.
* **lockstep** (``speed=None``, ``--speed max``): the camera drives. Before frame *i* is shown, the
  previous frame has been processed and recorded, and every telemetry sample up to frame *i*'s
  capture time has been applied; nothing depends on this computer's speed, so two replays are equal.

The camera thread calls :meth:`show` and :meth:`finish`; the event loop calls :meth:`reach` (the
vehicle's telemetry), :meth:`frame_done` (the platform, per processed frame) and :meth:`now`. The
platform may set :attr:`ReplayTimeline.before_show` to act on the camera thread just before a frame
is shown (it replays the operator's commands to the processor there).
"""

from __future__ import annotations

import asyncio
import math
import threading
import time
from collections.abc import Callable

FOREVER = math.inf
_POLL_S = 0.1
"""How often a blocked camera thread looks at its stop flag."""


def parse_speed(text: str | float | None) -> float | None:
    """``max`` -> None (lockstep); a positive number -> that factor; raises ValueError otherwise."""
    if text is None:
        return 1.0
    if isinstance(text, str) and text.strip().lower() == "max":
        return None
    try:
        speed = float(text)
    except ValueError:
        speed = math.nan
    if not math.isfinite(speed) or speed <= 0:
        raise ValueError(f"speed must be a positive number or 'max', got {text!r}")
    return speed


class ReplayTimeline:
    """The replay's position on the recorded clock (thread-safe).

    Args:
        origin_ns: recorded time the replay starts at (the first telemetry sample or frame).
        speed: recorded seconds per real second; None for lockstep.
    """

    def __init__(self, origin_ns: int, speed: float | None) -> None:
        self.origin_ns = origin_ns
        self.speed = speed
        self._cond = threading.Condition()
        self._real_start_ns: int | None = None
        self._position: float = origin_ns
        self._settled: float = -FOREVER
        self._shown = 0
        self._done = 0
        self._wakers: list[Callable[[], None]] = []
        self.before_show: Callable[[int], None] | None = None
        """Called on the camera thread with a frame's capture time once it is due, before it is shown."""

    @property
    def lockstep(self) -> bool:
        return self.speed is None

    def now(self) -> int:
        """The recorded instant the replay is at."""
        if self.speed is None:
            with self._cond:
                return int(min(self._position, 2**62))
        elapsed = time.monotonic_ns() - self._start()
        return self.origin_ns + int(elapsed * self.speed)

    def real_ns(self, t_ns: int) -> int | None:
        """The instant (this computer's ``time.monotonic_ns()``) the recorded instant ``t_ns`` is due in a paced replay;
        None in lockstep, where the camera waits for the processor instead of the clock."""
        if self.speed is None:
            return None
        return self._start() + int((t_ns - self.origin_ns) / self.speed)

    # -- camera thread ---------------------------------------------------------------------------

    def show(self, t_ns: int, stop: threading.Event) -> bool:
        """Block until the frame captured at ``t_ns`` is due; False when ``stop`` was set meanwhile."""
        due = self._due(t_ns, stop)
        if due and self.before_show is not None:
            self.before_show(t_ns)
        return due

    def _due(self, t_ns: int, stop: threading.Event) -> bool:
        if self.speed is not None:
            delay_s = (t_ns - self.now()) / self.speed / 1e9
            return not (delay_s > 0 and stop.wait(delay_s)) and not stop.is_set()
        with self._cond:
            if not self._wait(lambda: self._done >= self._shown, stop):
                return False
            self._position = max(self._position, t_ns)
            self._wake()
            if not self._wait(lambda: self._settled >= t_ns, stop):
                return False
            self._shown += 1
        return True

    def finish(self, stop: threading.Event) -> None:
        """The camera has nothing more to show: once its last frame is done, the rest of the telemetry may go."""
        with self._cond:
            if self.speed is None and not self._wait(lambda: self._done >= self._shown, stop):
                return
            self._position = FOREVER
            self._wake()

    # -- event loop ------------------------------------------------------------------------------

    def frame_done(self) -> None:
        """A shown frame was processed and recorded (lockstep moves on only then)."""
        with self._cond:
            self._done += 1
            self._cond.notify_all()

    async def reach(self, t_ns: int) -> None:
        """Wait until telemetry recorded at ``t_ns`` is due; everything yielded before it counts as applied."""
        if self.speed is not None:
            delay_s = (t_ns - self.now()) / self.speed / 1e9
            if delay_s > 0:
                await asyncio.sleep(delay_s)
            return
        loop = asyncio.get_running_loop()
        moved = asyncio.Event()

        def waker() -> None:  # called from the camera thread
            loop.call_soon_threadsafe(moved.set)

        with self._cond:
            self._wakers.append(waker)
        try:
            while True:
                with self._cond:
                    if self._position >= t_ns:
                        return
                    self._settled = max(self._settled, self._position)
                    self._cond.notify_all()
                    moved.clear()
                await moved.wait()
        finally:
            with self._cond:
                self._wakers.remove(waker)

    def exhausted(self) -> None:
        """No telemetry is left to apply: the camera never waits for it again."""
        with self._cond:
            self._settled = FOREVER
            self._cond.notify_all()

    # -- inside ----------------------------------------------------------------------------------

    def _start(self) -> int:
        with self._cond:
            if self._real_start_ns is None:
                self._real_start_ns = time.monotonic_ns()
            return self._real_start_ns

    def _wait(self, predicate: Callable[[], bool], stop: threading.Event) -> bool:
        while not predicate():
            if stop.is_set():
                return False
            self._cond.wait(_POLL_S)
        return not stop.is_set()

    def _wake(self) -> None:
        self._cond.notify_all()
        for waker in tuple(self._wakers):
            waker()
