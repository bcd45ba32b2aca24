"""How many threads FFmpeg decodes a replayed file with: the count that replays faster, one on a tie.

FFmpeg's frame threading (one decoder thread per core) buys decoding speed with CPU: the threads hand every
frame to each other. A replay's capture thread already decodes while the reader processes the previous frame,
so one decoder thread is enough whenever decoding is not what limits the rate, and it costs less CPU. Where
the limit is depends on the processor, the video and the machine (on a 2-core machine the decoder's threads
compete with the processor's process), so it is measured, not guessed: :class:`DecoderThreads` replays a
window on each count, keeps the one that delivered more frames a second (one thread unless FFmpeg's is
:data:`FASTER_BY` faster) and tries the other again every :data:`RETRY_S`.

Measured on the 2-core benchmark machine, processor in its own process: the generated 640x480 scene through the
template processor replays at 1650 frames a second on one thread, 1310 on FFmpeg's two; real drone video at
1280x720 through position hold at 387 on one, 446 on FFmpeg's.
"""

from __future__ import annotations

from dataclasses import dataclass, field

SINGLE = 1
FFMPEG_DEFAULT = 0
"""OpenCV's ``CAP_PROP_N_THREADS`` for "FFmpeg's own choice" (frame threads, as many as cores)."""
WINDOW_S = 1.0
"""Frames are counted over windows this long (and of :data:`MIN_FRAMES` at least); the first one after opening is a
warm-up and not counted."""
MIN_FRAMES = 30
FASTER_BY = 1.05
"""FFmpeg's threads are kept only when they replay this much faster than one thread."""
RETRY_S = 30.0
"""How old the other count's rate may get before it is measured again (the processor or the video changed)."""


@dataclass
class DecoderThreads:
    """Chooses the decoder thread count from the rate each one replays at (times in monotonic seconds)."""

    threads: int = SINGLE
    rates: dict[int, tuple[float, float]] = field(default_factory=dict)
    """Frames a second measured on each count, and when."""
    _window_start: float | None = None
    _frames: int = 0
    _warmed_up: bool = False

    def frame(self, now: float) -> int | None:
        """Count one frame decoded; at the end of a window, the thread count to switch to (None: stay)."""
        if self._window_start is None:
            self._window_start = now
        self._frames += 1
        wall = now - self._window_start
        if wall < WINDOW_S or self._frames < MIN_FRAMES:
            return None
        rate, self._window_start, self._frames = self._frames / wall, now, 0
        if not self._warmed_up:
            self._warmed_up = True
            return None
        self.rates[self.threads] = (rate, now)
        other = FFMPEG_DEFAULT if self.threads == SINGLE else SINGLE
        other_rate, measured_at = self.rates.get(other, (0.0, float("-inf")))
        if now - measured_at > RETRY_S:
            return other  # a window on the other count
        single, ffmpeg = (rate, other_rate) if self.threads == SINGLE else (other_rate, rate)
        best = FFMPEG_DEFAULT if ffmpeg > FASTER_BY * single else SINGLE
        return None if best == self.threads else best

    def switched(self, threads: int, now: float) -> None:
        """The decoder now runs on ``threads``; a new window starts."""
        self.threads, self._window_start, self._frames = threads, now, 0
