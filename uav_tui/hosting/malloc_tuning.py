"""glibc's allocator, set for processes that allocate and free megabytes of images every frame.

By default glibc serves a large block (an image, a detector's input tensor) from its heap once one of that size
was freed, but gives the heap's free top back to the kernel as soon as it exceeds twice that size. A
processor that frees several such blocks at the end of each frame (YOLO: letterbox, float tensor, outputs)
crosses that line every frame, so every frame maps its memory anew and page-faults it in again: at 640x480
that cost YOLO 15 % of its frame rate in its own process. Keeping up to :data:`TRIM_THRESHOLD` of free heap and
serving blocks below :data:`MMAP_THRESHOLD` from it stops that churn, for at most that much more resident memory.

Only glibc has these settings; elsewhere nothing changes. A user's own ``MALLOC_*`` variables win.
"""

from __future__ import annotations

import ctypes
import logging
import os
from collections.abc import Mapping

logger = logging.getLogger(__name__)

MMAP_THRESHOLD = 32 * 1024 * 1024
"""Blocks below this come from the heap (glibc's own upper bound for its adaptive threshold): a 4K frame is 24 MB."""

TRIM_THRESHOLD = 64 * 1024 * 1024
"""Free memory at the top of a heap kept for the next frame rather than returned to the kernel."""

ENVIRONMENT = {"MALLOC_MMAP_THRESHOLD_": str(MMAP_THRESHOLD), "MALLOC_TRIM_THRESHOLD_": str(TRIM_THRESHOLD)}
"""The same settings for a process about to start (glibc reads them once, at its start)."""

_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3


def child_environment(environ: Mapping[str, str]) -> dict[str, str]:
    """``environ`` plus :data:`ENVIRONMENT`, unless it sets a ``MALLOC_`` variable or a malloc tunable itself."""
    if _user_tuned(environ):
        return dict(environ)
    return {**environ, **ENVIRONMENT}


def tune_this_process() -> bool:
    """Apply the settings to this process with ``mallopt``; False where there is no glibc or the user tuned it."""
    if _user_tuned(os.environ):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt  # this process's own symbols: no ldconfig run to find libc
    except (OSError, AttributeError):  # no mallopt (macOS): leave the allocator alone
        return False
    applied = mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1 and mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1
    if not applied:
        logger.debug("mallopt refused the image-friendly malloc settings; glibc's defaults stay")
    return applied


def _user_tuned(environ: Mapping[str, str]) -> bool:
    return "glibc.malloc." in environ.get("GLIBC_TUNABLES", "") or any(name.startswith("MALLOC_") for name in environ)
