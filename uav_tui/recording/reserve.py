"""Disk space held for a run's last write, and the space a killed run left held.

A run keeps :data:`RESERVE_BYTES` in ``.reserved-for-run.json`` from its start to its end and frees them just
before it finishes ``run.json``, so a disk that filled up meanwhile still takes the run's summary. The run holds an
advisory lock (``flock``) on the file while it lasts; the system releases it when the process ends in any way.
A run that was killed (SIGKILL, a power cut) leaves the file behind: the next run under the same ``runs_dir``
finds it unlocked and deletes it (:func:`free_stale_reserves`), while a run going on in another process keeps
its own.
"""

from __future__ import annotations

import contextlib
import fcntl
import logging
import os
from pathlib import Path

logger = logging.getLogger(__name__)

RESERVE = ".reserved-for-run.json"
RESERVE_BYTES = 256 * 1024


class DiskReserve:
    """Holds ``RESERVE_BYTES`` in ``run_dir/.reserved-for-run.json``, locked, until :meth:`release`.

    Raises:
        OSError: the file cannot be written (the disk is full already, the folder is read-only).
    """

    def __init__(self, run_dir: Path) -> None:
        self.path = run_dir / RESERVE
        self._fd: int | None = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
        with contextlib.suppress(OSError):  # a filesystem without locks: nothing there is ever taken for stale
            fcntl.flock(self._fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        try:
            os.write(self._fd, bytes(RESERVE_BYTES))
        except OSError:
            self.release()
            raise

    def release(self) -> None:
        """Free the space (delete the file, then unlock it). Idempotent."""
        self.path.unlink(missing_ok=True)
        fd, self._fd = self._fd, None
        if fd is not None:
            os.close(fd)


def free_stale_reserves(runs_dir: Path) -> int:
    """Delete the reserves of runs under ``runs_dir`` whose process is gone (no lock held); returns how many."""
    freed = 0
    for path in runs_dir.glob(f"*/{RESERVE}"):
        try:
            fd = os.open(path, os.O_RDONLY)
        except OSError:  # deleted meanwhile by its own run
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # held: that run is going on (or locks fail here: then nothing is known to be stale)
            os.close(fd)
            continue
        try:
            with contextlib.suppress(FileNotFoundError):
                path.unlink()
                freed += 1
                logger.info("freed %s, left by a run that did not end normally", path)
        finally:
            os.close(fd)
    return freed

