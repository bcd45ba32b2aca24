"""The log records a processor makes on the thread host's thread, within a line budget.

In its own process a processor's log records come to the platform as lines of its output, which pass a
:class:`~uav_tui.output.line_budget.LineBudget` with its prints. On a thread of the platform they went straight to the
platform's log handlers, a flood of them with them. :class:`ThreadLogBudget` is a filter on those handlers: the
records made on one thread pass within a budget of their own (the burst, then one a second), and the count of
those left out is said; every other thread's records pass untouched.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable

from uav_tui.output.line_budget import LineBudget

_VERDICT = "_uav_tui_budget_verdict"
"""Set on a record once it was judged, so that each of several handlers does not count it again."""


class ThreadLogBudget(logging.Filter):
    """Lets the records made on ``thread`` through the root logger's handlers within a line budget.

    Create it on the event loop's thread (its budget says the count there), and install it before ``thread``
    starts. Handlers added to the root logger after :meth:`install` are not covered.
    """

    def __init__(self, thread: threading.Thread, say_left_out: Callable[[int], None]) -> None:
        super().__init__()
        self._thread = thread
        self._budget: LineBudget[logging.LogRecord] = LineBudget(self._passed, say_left_out)
        self._verdict = False
        self._judging = threading.local()
        self._handlers: list[logging.Handler] = []

    def install(self) -> None:
        self._handlers = list(logging.getLogger().handlers)
        for handler in self._handlers:
            handler.addFilter(self)

    def remove(self) -> None:
        """Take the filter off again and say the count of what was left out."""
        for handler in self._handlers:
            handler.removeFilter(self)
        self._handlers = []
        self._budget.close()

    def filter(self, record: logging.LogRecord) -> bool:
        # The thread itself, not its ident: a thread started after ``thread`` ended may get the same ident.
        if threading.current_thread() is not self._thread or getattr(self._judging, "active", False):
            return True  # another thread's, or said while judging one (the count's event)
        verdict = record.__dict__.get(_VERDICT)
        if verdict is None:
            self._judging.active, self._verdict = True, False
            try:
                self._budget.line(record)
            finally:
                self._judging.active = False
            verdict = record.__dict__[_VERDICT] = self._verdict
        return bool(verdict)

    def _passed(self, record: logging.LogRecord) -> None:
        self._verdict = True
