"""A network handler's unexpected failure costs the one message that caused it, never the handler.

The MAVLink camera component and the web routes validate every field before use; what still raises
there is a bug. They catch it, answer that one message with a failure, and report it here: the first
failure of each kind (exception type and the line that raised it) goes to the log with its traceback,
and every failure becomes an error event within a line budget (a flood of bad datagrams is a count,
not a line each).
"""

from __future__ import annotations

import logging

from controllers.errors import FailureKinds
from uav_tui.events import EventLog
from uav_tui.output.line_budget import LineBudget
from uav_tui.output.text import shorten

logger = logging.getLogger(__name__)

BURST = 3
PER_S = 0.1
"""Failure events: 3 said at once, then one every 10 s; the rest are counted and the count is said."""


class HandlerFailures:
    """Reports the unexpected failures of one network handler (call on the event loop).

    Args:
        events: where the operator reads them.
        name: the handler, as the operator knows it (``CameraTracking(udpin:0.0.0.0:14580)``).
    """

    def __init__(self, events: EventLog, name: str) -> None:
        self.events = events
        self.name = name
        self.count = 0
        """Failures so far."""
        self._kinds = FailureKinds()
        self._budget = LineBudget(self._say, self._say_left_out, burst=BURST, per_s=PER_S)

    def failed(self, what: str, exc: BaseException) -> None:
        """Handling ``what`` (the message and who sent it) raised ``exc``; the handler goes on with the next one."""
        self.count += 1
        if kind := self._kinds.first(exc):
            logger.error("%s: %s failed (%s)", self.name, what, kind, exc_info=exc)
        self._budget.line(f"{self.name}: {what} failed: {type(exc).__name__}: {shorten(str(exc), 200)} "
                          "(a bug: the message was refused, the handler goes on)")

    def close(self) -> None:
        """Say the count of failures not yet said."""
        self._budget.close()

    def _say(self, line: str) -> None:
        self.events.emit("error", "web", line)

    def _say_left_out(self, count: int) -> None:
        self.events.emit("error", "web", f"{self.name}: {count} more handler failures ({self.count} in all)")

