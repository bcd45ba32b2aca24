"""Output to a terminal that may stop taking it: ``write`` never waits.

An SSH connection stalled on bad Wi-Fi stops reading; once the terminal's buffer is full, a plain
``write`` on the event loop waits with it, and the flight link, the watchdog and the hold wait too.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any, Protocol

MAX_BACKLOG_CHARS = 512 * 1024
"""Output not yet taken by the terminal beyond which writes are dropped (a few full screens)."""


class Writable(Protocol):
    def write(self, text: str, /) -> object: ...
    def flush(self) -> object: ...


class TerminalOutput:
    """Writes to ``file`` from a thread of its own, so ``write`` never waits for the terminal.

    Writes that would take the backlog past ``max_backlog`` characters are dropped, whole (never a
    piece of a line or of an escape sequence); writes of at most ``kept_write_chars`` (a screen's
    terminal modes) are always kept. Once the terminal has taken everything, ``on_drained(dropped)``
    is called (on the writer thread) if writes were dropped, with how many. A write that fails (the
    terminal is gone) is dropped and reported to ``on_error``.

    It can stand in for ``sys.stdout`` or a :class:`logging.StreamHandler`'s stream: ``flush`` returns at
    once, and other file attributes (``encoding``, ``isatty``, ``fileno``) are ``file``'s.
    """

    def __init__(
        self,
        file: Writable,
        on_drained: Callable[[int], None],
        on_error: Callable[[OSError], None],
        *,
        max_backlog: int = MAX_BACKLOG_CHARS,
        kept_write_chars: int = 0,
        name: str = "terminal-output",
    ) -> None:
        self._file = file
        self._on_drained = on_drained
        self._on_error = on_error
        self._max_backlog = max_backlog
        self._kept_write_chars = kept_write_chars
        self._pending: list[str] = []
        self._backlog = 0
        self._dropped = 0
        self._closing = False
        self._ready = threading.Condition()
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def write(self, text: str) -> int:
        """Queue ``text`` for the writer thread (or drop it, counted, when the backlog is full); ``len(text)``
        as a text file returns, written or not."""
        with self._ready:
            if len(text) > self._kept_write_chars and self._backlog and self._backlog + len(text) > self._max_backlog:
                self._dropped += 1
                return len(text)
            self._pending.append(text)
            self._backlog += len(text)
            self._ready.notify()
        return len(text)

    def flush(self) -> None:
        """Nothing to do: the writer thread flushes after each batch."""

    def __getattr__(self, name: str) -> Any:
        return getattr(self._file, name)

    def close(self, timeout: float) -> None:
        """Write what is pending, waiting at most ``timeout`` s (the terminal may be stalled), then stop."""
        with self._ready:
            self._closing = True
            self._ready.notify()
        self._thread.join(timeout)

    def _run(self) -> None:
        while True:
            with self._ready:
                self._ready.wait_for(lambda: self._pending or self._closing)
                if not self._pending:
                    return
                text, self._pending = "".join(self._pending), []
            try:
                self._file.write(text)  # may wait for the terminal: only this thread waits
                self._file.flush()
            except OSError as exc:
                self._on_error(exc)
            with self._ready:
                self._backlog -= len(text)
                dropped = self._dropped if not self._pending else 0
                if dropped:
                    self._dropped = 0
            if dropped:
                self._on_drained(dropped)
