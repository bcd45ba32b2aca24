"""Camera sources, chosen by one URI string.

``open_source("file:flight.mp4")`` returns an opened :class:`CameraSource`. Each scheme maps to a
module that is imported only when asked for, so ``picamera2`` is loaded only for ``picam:``.
"""

from __future__ import annotations

import importlib
from typing import Any

from sources.base import CameraSource, CaptureSource, WarmsUp
from sources.buffer import Frame, FrameBuffer
from sources.errors import SourceError, SourceUriError
from sources.uri import SourceUri

SCHEMES: dict[str, str] = {
    "file": "sources.file:FileSource",
    "synthetic": "sources.synthetic:SyntheticSource",
    "usb": "sources.usb:UsbSource",
    "picam": "sources.picam:PicamSource",
    "rtsp": "sources.network:NetworkSource",
    "rtsps": "sources.network:NetworkSource",
    "http": "sources.network:NetworkSource",
    "https": "sources.network:NetworkSource",
    "sim": "sources.sim_camera:SimCameraSource",
    "run": "sources.run:RunSource",
}
"""URI scheme -> ``module:Class``. Each class has ``from_uri(SourceUri, **context)``."""

__all__ = ["SCHEMES", "CameraSource", "CaptureSource", "Frame", "FrameBuffer", "create_source", "open_source",
           "warm_up_source"]


def create_source(uri: str, **context: Any) -> CameraSource:
    """Build the source ``uri`` names without opening it.

    ``context`` passes platform objects a source may need (``pose_provider`` for ``sim:``).
    """
    parsed = SourceUri.parse(uri)
    target = SCHEMES.get(parsed.scheme)
    if target is None:
        known = ", ".join(f"{name}:" for name in SCHEMES)
        raise SourceUriError(f"unknown camera scheme {parsed.scheme!r} in {uri!r}; known: {known}", key="source")
    module_name, class_name = target.split(":")
    cls = getattr(importlib.import_module(module_name), class_name)
    source: CameraSource = cls.from_uri(parsed, **context)
    return source


def warm_up_source(uri: str) -> None:
    """Do the slow one-off preparation of the source ``uri`` names, if its class has any (``warm_up``), so that
    it can overlap other start-up work; blocks. Mistakes in ``uri`` are left for :func:`open_source` to report."""
    try:
        parsed = SourceUri.parse(uri)
        module_name, class_name = SCHEMES[parsed.scheme].split(":")
        cls = getattr(importlib.import_module(module_name), class_name)
        if isinstance(cls, WarmsUp):  # a class with a static warm_up(uri)
            cls.warm_up(parsed)
    except (KeyError, SourceError):
        return


def open_source(uri: str, **context: Any) -> CameraSource:
    """Build and open the source ``uri`` names; raises SourceError with the reason when it fails."""
    source = create_source(uri, **context)
    if not source.open():
        reason = source.get_properties().get("last_error") or "unknown reason"
        source.close()
        raise SourceError(f"cannot open camera {uri!r}: {reason}")
    return source
