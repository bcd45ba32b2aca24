"""The camera contract and the capture-thread base every built-in source shares."""

from __future__ import annotations

import logging
import threading
import time
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from sources.buffer import FrameBuffer

if TYPE_CHECKING:
    from sources.uri import SourceUri
    from uav_values.camera import CameraModel

logger = logging.getLogger(__name__)

RETRY_DELAYS_S = (0.25, 0.5, 1.0, 2.0, 4.0)
"""Back-off between reopen attempts after a device failure; the last value repeats."""


@runtime_checkable
class CameraSource(Protocol):
    """What the platform needs from a camera.

    ``open`` starts capturing into ``buffer``; ``read`` returns the newest BGR uint8 frame without
    ever waiting on the device; ``close`` is idempotent.
    """

    buffer: FrameBuffer

    def open(self) -> bool: ...
    def read(self) -> tuple[bool, np.ndarray | None]: ...
    def get_frame_size(self) -> tuple[int, int]: ...
    def close(self) -> None: ...
    def get_properties(self) -> dict[str, Any]: ...


@runtime_checkable
class KnowsCameraModel(Protocol):
    """A source that can know its own camera model (``sim:`` its renderer's); the platform asks it first."""

    def camera_model(self) -> CameraModel | None:
        """The model, or None: this source cannot know (the configured one is taken, if any)."""
        ...


@runtime_checkable
class WarmsUp(Protocol):
    """A source class with a slow one-off preparation (``sim:`` builds its ground) that may run before it is
    built, overlapping the platform's other start-up work (:func:`sources.warm_up_source`)."""

    def warm_up(self, uri: SourceUri) -> None: ...


class CaptureSource:
    """A source whose device is read by one background thread into a :class:`FrameBuffer`.

    Subclasses implement the hooks only; the lifecycle, the thread, error counting and the
    reconnect back-off live here::

        _open_device()   open the device, set width/height/fps; raise SourceError with advice
        _grab()          block for the next frame; None when the read failed
        _close_device()  release the device (called once per successful open)
        _capture_times() the recorded capture times of the grabbed image (replays only)
        _extra_properties()  source-specific entries for get_properties()

    A failed ``_grab`` marks the source stalled, closes the device and reopens it with back-off
    until it delivers again or the source is closed; it never dies silently.
    """

    kind = "base"
    """Short name of the source type, as in its URI scheme."""

    def __init__(self, uri: str, device: str) -> None:
        self.uri = uri
        self.device = device
        self.buffer = FrameBuffer()
        self.width = 0
        self.height = 0
        self.fps = 0.0
        self.errors = 0
        self.last_error: str | None = None
        self.stalled_since: float | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._device_lock = threading.Lock()
        self._device_open = False

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.device})"

    # -- the contract ---------------------------------------------------------------------------

    def open(self) -> bool:
        """Open the device and start the capture thread; False (reason in ``last_error``) on failure."""
        with self._lock:
            if self._thread is not None:
                return True
            try:
                self._open_device()
            except Exception as exc:  # noqa: BLE001 - the reason is the caller's to report (not logged twice)
                self.errors += 1
                self.last_error = str(exc)
                return False
            self._device_open = True
            self._stop.clear()
            self._thread = threading.Thread(target=self._capture_loop, name=f"capture-{self.kind}:{self.device}",
                                            daemon=True)
            self._thread.start()
            logger.info("%r opened: %dx%d @ %.1f fps", self, self.width, self.height, self.fps)
            return True

    def read(self) -> tuple[bool, np.ndarray | None]:
        """The newest frame, never waiting for the device."""
        frame = self.buffer.latest()
        return (False, None) if frame is None else (True, frame.image)

    def get_frame_size(self) -> tuple[int, int]:
        """(width, height) as granted by the device."""
        return self.width, self.height

    def close(self) -> None:
        """Stop the thread and release the device; safe to call twice."""
        with self._lock:
            thread, self._thread = self._thread, None
            self._stop.set()
        if thread is not None and thread is not threading.current_thread():
            thread.join(timeout=5)
            if thread.is_alive():  # stuck in a device call (an open or read timeout): it releases on its way out
                logger.warning("%r: capture thread still busy in the device; it will release it when it returns", self)
                return
        self._release_device()

    def get_properties(self) -> dict[str, Any]:
        """Kind, device, granted size and fps, counters, last error and stall time."""
        return {
            "kind": self.kind,
            "uri": self.uri,
            "device": self.device,
            "width": self.width,
            "height": self.height,
            "fps": self.fps,
            "frames_captured": self.buffer.captured,
            "frames_dropped": self.buffer.overwritten,
            "errors": self.errors,
            "last_error": self.last_error,
            "stalled_since": self.stalled_since,
            "running": self._thread is not None,
            **self._extra_properties(),
        }

    def camera_model(self) -> CameraModel | None:
        """The camera model this source knows for itself (``sim:`` its renderer's); None: it cannot know.

        The platform then takes the configured one (``[camera]``), or there is none.
        """
        return None

    # -- hooks ----------------------------------------------------------------------------------

    def _open_device(self) -> None:
        raise NotImplementedError

    def _grab(self) -> np.ndarray | None:
        raise NotImplementedError

    def _close_device(self) -> None:
        """Release the device; nothing by default."""

    def _capture_times(self) -> tuple[int | None, int | None]:
        """(monotonic, wall) ns of the image ``_grab`` just returned, where the source knows them better
        than "now" (a replay returns recorded ones, a rendered camera the instant it shows); None: now."""
        return None, None

    def _extra_properties(self) -> dict[str, Any]:
        return {}

    # -- the thread -----------------------------------------------------------------------------

    def _capture_loop(self) -> None:
        try:
            while not self._stop.is_set():
                reason = "no frame from the device"
                try:
                    image = self._grab()
                except Exception as exc:  # noqa: BLE001 - counted and reported, then recovered
                    image, reason = None, f"read failed: {exc}"
                if self._stop.is_set():
                    break
                if image is not None:
                    self.stalled_since = None
                    self.buffer.put(image, *self._capture_times())
                else:
                    self._recover(reason)
        finally:
            self._release_device()

    def _release_device(self) -> None:
        """Close the device if it is open; safe from the capture thread and from ``close`` at once."""
        with self._device_lock:
            if self._device_open:
                self._device_open = False
                self._close_device()

    def _recover(self, reason: str) -> None:
        """Mark the stall, then close and reopen the device with back-off until it works again."""
        if self.stalled_since is None:
            self.stalled_since = time.time()
        self._fail(reason)
        attempt = 0
        while not self._stop.is_set():
            self._release_device()
            if self._stop.wait(RETRY_DELAYS_S[min(attempt, len(RETRY_DELAYS_S) - 1)]):
                return
            attempt += 1
            try:
                self._open_device()
            except Exception as exc:  # noqa: BLE001
                self._fail(f"reopen attempt {attempt} failed: {exc}")
                continue
            self._device_open = True
            logger.info("%r reopened after %d attempt(s)", self, attempt)
            return

    def _fail(self, reason: str) -> None:
        self.errors += 1
        if reason != self.last_error:
            logger.warning("%r: %s", self, reason)
        self.last_error = reason
