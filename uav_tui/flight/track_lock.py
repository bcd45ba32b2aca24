"""The operator's lock on one track: the locked track drives the vehicle or its gimbal, whichever processor detects
it.

``lock ID`` (a script line, the web page's click inside a track's box, a ground station's CAMERA_TRACK_POINT inside
one) locks the track numbered ``ID`` on the newest frame. From the next frame on, :meth:`TrackLock.steer` (on the
loop, before the autonomy gate) makes that frame's vector and box the locked track's: the trackers' steering
(:class:`~processors.steering.Steering` at :data:`~processors.follow.FOLLOW_GAIN`, eased in by
:class:`~processors.steering.Ramp`) towards its box, or None while it is not seen. The processor's own vector is
not used meanwhile. The gate then judges the vector as any processor's (autonomy, the vehicle's mode, the frame's
age, the envelope), and the envelope's ``lost_after_s`` sees the lock's box as the processor's. With the camera on
the gimbal the vehicle holds instead (no vector) and the frame's gimbal pointing is the trackers' ``follow="gimbal"``
one (:class:`~processors.gimbal_steering.GimbalSteering`) towards the box, from the gimbal's pitch at the frame's
capture: the gimbal relay sends it as a processor's, and stops the gimbal while the track is not seen.

The lock lives on the platform's side, with the tracks (:mod:`uav_tui.hosting.tracks`), so a researcher's detector
gets it without a line of code; on the loop, because the operator's commands, the gate and the envelope are there
(the processor's process only sees frames). Its cost there (scripts/bench_lock.py, scripts/results/lock.json): 25-45 us
a frame while locked (one look, :mod:`uav_tui.flight.appearance`), 30-70 us while lost whatever the detections (a
look of each of the :data:`NEAREST` new tracks at most).

When the locked track's number is missing from a frame, the track is lost. The new tracks (not there while the
locked one was seen) of its label are then compared, nearest to where it went first (at most :data:`NEAREST`); the
first with a look at least :data:`SAME_LOOK` alike the kept one is taken as the locked object under its new number
(the tracker numbered it anew: it was hidden longer than the tracker keeps a track, or crossed another). Where it
went comes first because look-alikes are common (the ``sim:`` camera's cars share one roof), and the look keeps a
nearer object of another colour from being taken. The lock is released by ``unlock``, by any vehicle command, and by
a loss longer than the envelope's ``lost_after_s`` (without one, a lost lock waits for its track).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

import msgspec
import numpy as np

from processors.follow import FOLLOW_GAIN
from processors.gimbal_steering import GimbalSteering
from processors.steering import Ramp, Steering, Vector
from uav_tui.errors import CommandError
from uav_tui.flight.appearance import Look, blend, likeness, look
from uav_values.box import PixelBox
from uav_values.detections import Detected

if TYPE_CHECKING:
    from uav_tui.events import EventLog
    from uav_tui.hosting.host import ProcessedFrame
    from uav_tui.hosting.wire import FrameOutcome
    from uav_values.camera import CameraModel
    from uav_values.gimbal import GimbalPointing

SAME_LOOK = 0.6
"""The least likeness (:func:`~uav_tui.flight.appearance.likeness`) a new track needs to be taken as the lost one.
Measured (scripts/bench_lock.py): the ``sim:`` camera's car 2 s later, turned, 0.79; a red car in a shadow 0.84; a
blue car 0.0; the ground 0.07; another of the simulator's cars, with the same roof, 0.57."""

NEAREST = 4
"""While lost, only the new tracks this near (in number) to where the locked one was last seen are compared: a
hidden object comes back near where it went, and the loop's cost stays under 0.1 ms a frame whatever the detections
(0.7 ms with 31 new tracks compared, measured)."""

BRIEF_LOSS_S = 0.5
"""A loss shorter than this (a detector's missed frame) is not said, and the next vector goes on from the speed
reached instead of easing in again from standstill (the last vector, ``t`` = 0.5 s, is still flying meanwhile)."""

LOOK_WEIGHT = 0.2
"""How far each frame the locked track is seen moves its kept look (the look follows a slow change of light)."""

DOWN_TILT_DEG = 60.0
"""A camera tilted at least this far below the nose steers as a down camera; less, as a forward one."""


class LockState(StrEnum):
    """Where the lock is."""

    OFF = "off"
    LOCKED = "locked"  # the locked track is on the newest frame
    LOST = "lost"  # it is not; a new track that looks like it is taken


@dataclass(frozen=True, slots=True)
class LockStatus:
    """The lock as the interfaces show it."""

    state: LockState = LockState.OFF
    track_id: int | None = None
    label: str = ""
    lost_s: float = 0.0
    """Seconds (on the frames' clock) since the locked track was last seen, while lost."""
    renumbered: int = 0
    """How often the locked object was taken back under a new number."""

    def __str__(self) -> str:
        """``locked on #3 car``, ``#3 car lost 1.2 s``, ``off``."""
        if self.state is LockState.LOCKED:
            return f"locked on #{self.track_id} {self.label}"
        if self.state is LockState.LOST:
            return f"#{self.track_id} {self.label} lost {self.lost_s:.1f} s"
        return "off"


class TrackLock:
    """One lock at a time: :meth:`lock`, :meth:`release`, and :meth:`steer` on every processed frame.

    Args:
        events: where a lock, its loss, a new number and a release are said.
        lost_after_s: the envelope's ``lost_after_s`` now (0: no release for a loss).
        gimbal_pitch: the gimbal's pitch from the horizon (degrees) at a capture time (monotonic ns), None when not
            known (then the image offsets are taken as the angles to turn).
    """

    def __init__(self, events: EventLog, lost_after_s: Callable[[], float],
                 gimbal_pitch: Callable[[int], float | None] = lambda t_ns: None) -> None:
        self.events = events
        self.lost_after_s = lost_after_s
        self.gimbal_pitch = gimbal_pitch
        self.state = LockState.OFF
        self.track_id: int | None = None
        self.label = ""
        self.renumbered = 0
        self.vector: Vector | None = None
        """The vector the lock made the newest frame's (None while lost or off)."""
        self.newest: tuple[Detected, ...] = ()
        """The newest processed frame's detections (what ``lock`` and :meth:`track_at` choose from)."""
        self._look: Look | None = None
        self._seen_s = 0.0
        """The frame time (s) the locked track was last seen."""
        self._now_s = 0.0
        self._present: frozenset[int] = frozenset()
        """The other tracks on the frame the locked one was last seen on: none of them can be it."""
        self._steering = Steering()
        self._gimbal: GimbalSteering | None = None
        """The gimbal's steering while the locked camera rides the gimbal, else None (the vehicle steers)."""
        self._camera: CameraModel | None = None
        self._ramp = Ramp()
        self._ref_height = 0.0
        self._box: PixelBox = (0, 0, 1, 1)
        """Where the locked track was last seen."""
        self._said_lost = False

    def status(self) -> LockStatus:
        """The lock now, as the interfaces show it."""
        lost = self._now_s - self._seen_s if self.state is LockState.LOST else 0.0
        return LockStatus(self.state, self.track_id, self.label, lost, self.renumbered)

    def track_at(self, x: float, y: float) -> int | None:
        """The track whose box on the newest frame holds the pixel (x, y) (the smallest, where boxes overlap)."""
        inside = [d for d in self.newest if d.track_id is not None
                  and d.box[0] <= x < d.box[0] + d.box[2] and d.box[1] <= y < d.box[1] + d.box[3]]
        return min(inside, key=lambda d: d.box[2] * d.box[3]).track_id if inside else None

    def lock(self, track_id: int, camera: CameraModel | None, origin: str = "platform") -> str:
        """Lock on the track ``track_id`` of the newest frame; CommandError when it has none of that number."""
        found = next((d for d in self.newest if d.track_id == track_id), None)
        if found is None:
            ids = sorted(d.track_id for d in self.newest if d.track_id is not None)
            raise CommandError(f"lock {track_id}: no track {track_id} on the newest frame (" + (
                f"its tracks: {', '.join(f'#{i}' for i in ids)})" if ids else "it has no tracks)"), key="lock")
        if self.state is not LockState.OFF:
            self.release(f"locked on #{track_id} instead", origin)
        tilt = 90.0 if camera is None else camera.mount.tilt_deg
        self._steering = Steering("down" if camera is None or tilt >= DOWN_TILT_DEG else "forward", FOLLOW_GAIN)
        self._gimbal = GimbalSteering() if camera is not None and camera.mount.gimbal else None
        self._camera = camera
        self._ramp, self._ref_height = Ramp(), float(found.box[3])
        self.state, self.track_id, self.label, self.renumbered = LockState.LOCKED, track_id, found.label, 0
        self._look, self._seen_s, self._box = None, self._now_s, found.box
        self._present = frozenset(d.track_id for d in self.newest if d.track_id not in (None, track_id))
        return f"locked on track #{track_id} ({found.label})"

    def release(self, reason: str, origin: str = "platform") -> bool:
        """Release the lock (True) saying why; False when there was none."""
        if self.state is LockState.OFF:
            return False
        self.events.emit("info", "autonomy", f"lock on #{self.track_id} {self.label} released: {reason}", origin)
        self.state, self.track_id, self._look = LockState.OFF, None, None
        return True

    def steer(self, result: ProcessedFrame) -> ProcessedFrame:
        """Note ``result``'s detections; while locked, return a copy whose outcome's vector (the camera on the
        gimbal: its gimbal pointing, and no vector) and box are the locked track's (None each while it is not seen;
        ``result`` stays as the processor made it), else ``result``; :attr:`held` is then the lock after it."""
        outcome = result.outcome
        self.newest = outcome.detections or ()
        self._now_s = result.frame.t_mono_ns / 1e9
        if self.state is LockState.OFF:
            self.vector = None
            return result
        image = result.frame.image
        found = next((d for d in self.newest if d.track_id == self.track_id), None) or self._taken_back(image)
        if found is not None:
            self.state, self._seen_s, self._box, self._said_lost = LockState.LOCKED, self._now_s, found.box, False
            self._look = blend(self._look, look(image, found.box), LOOK_WEIGHT)
            self._present = frozenset(d.track_id for d in self.newest if d.track_id not in (None, self.track_id))
            size, pointing = (image.shape[1], image.shape[0]), None
            if self._gimbal is None:
                self.vector = self._ramp(self._steering.vector(found.box, size, self._ref_height), self._now_s)
            else:
                self.vector = None
                pointing = self._gimbal.rates(found.box, size, self._camera, self.gimbal_pitch(result.frame.t_mono_ns))
            return dataclasses.replace(result, outcome=self._aimed(outcome, found.box, pointing))
        self.state, lost_s = LockState.LOST, self._now_s - self._seen_s
        self.vector = None if lost_s < BRIEF_LOSS_S or self._gimbal is not None else self._ramp(None, self._now_s)
        if lost_s >= BRIEF_LOSS_S and not self._said_lost:
            self._said_lost = True
            self.events.emit("warning", "autonomy", f"lock: #{self.track_id} {self.label} lost")
        limit = self.lost_after_s()
        if limit and lost_s > limit:
            self.release(f"not seen for {limit:g} s (lost_after_s)")
        return dataclasses.replace(result, outcome=self._aimed(outcome, None, None))

    @property
    def held(self) -> LockStatus | None:
        """The lock's status while it is on (what frames.csv records of the newest frame), else None."""
        return None if self.state is LockState.OFF else self.status()

    def _aimed(self, outcome: FrameOutcome, box: PixelBox | None, pointing: GimbalPointing | None) -> FrameOutcome:
        """A copy of ``outcome`` with the lock's box, its vector and (the camera on the gimbal) its pointing."""
        outputs = outcome.outputs if self._gimbal is None else dataclasses.replace(outcome.outputs, gimbal=pointing)
        return msgspec.structs.replace(outcome, box=box, vector=self.vector, outputs=outputs)

    def _taken_back(self, image: np.ndarray) -> Detected | None:
        """The new track nearest where the lost one went that looks alike enough (its number is then the lock's)."""
        if self._look is None:
            return None
        new = [d for d in self.newest if d.track_id is not None and d.track_id not in self._present
               and d.label == self.label]
        for found in sorted(new, key=self._away)[:NEAREST]:
            seen = look(image, found.box)
            alike = 0.0 if seen is None else likeness(self._look, seen)
            if alike >= SAME_LOOK:
                self.events.emit("info", "autonomy", f"lock: #{self.track_id} {self.label} is now #{found.track_id} "
                                 f"(look {alike:.2f} alike)")
                self.track_id, self.renumbered = found.track_id, self.renumbered + 1
                return found
        return None

    def _away(self, found: Detected) -> float:
        """Pixels from the centre of where the locked track was last seen to ``found``'s."""
        (x, y, w, h), (fx, fy, fw, fh) = self._box, found.box
        return math.hypot(fx + fw / 2 - x - w / 2, fy + fh / 2 - y - h / 2)
