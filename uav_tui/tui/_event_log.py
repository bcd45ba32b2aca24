"""The event log panel: operator commands, autonomy decisions, warnings and errors, newest last; and what
the processor prints."""

from __future__ import annotations

import threading
import time
from typing import ClassVar

from rich.style import Style
from rich.text import Text
from textual import events
from textual.message import Message
from textual.widgets import RichLog

from uav_tui.events import Event
from uav_tui.output.line_budget import LineBudget, LineSplitter
from uav_tui.output.text import safe, shorten

PRINT_CHARS = 500
"""A longer printed line is cut."""

LEVEL_MARK = {"info": " ", "warning": "!", "error": "X"}
"""One character per level, so the log reads without colours too."""


class EventLogView(RichLog):
    """Shows :class:`~uav_tui.events.Event` s as ``HH:MM:SS ! kind: message`` lines."""

    COMPONENT_CLASSES: ClassVar[set[str]] = {"log--time", "log--warning", "log--error"}
    DEFAULT_CSS = """
    EventLogView {
        border-top: solid $primary; border-title-color: $text-primary; border-title-style: bold;
        height: 1fr; padding: 0 1; background: $surface; scrollbar-size-vertical: 1;
        & > .log--time { color: $text-muted; }
        & > .log--warning { color: $text-warning; }
        & > .log--error { color: $text-error; text-style: bold; }
    }
    """

    class Printed(Message):
        """A printed line within the budget, or (``left_out``) how many were not shown."""

        def __init__(self, line: str = "", left_out: int = 0) -> None:
            super().__init__()
            self.line, self.left_out = line, left_out

    def __init__(self, *, id: str | None = None) -> None:
        super().__init__(id=id, max_lines=500, min_width=20, wrap=True, markup=False, auto_scroll=True)
        self._printed: LineBudget[tuple[bool, str]] = LineBudget(
            lambda line: self.post_message(self.Printed(line=_printed_line(*line))),
            lambda count: self.post_message(self.Printed(left_out=count)))
        self._lines = {False: LineSplitter("\n", PRINT_CHARS), True: LineSplitter("\n", PRINT_CHARS)}
        """What was printed to stdout (False) and stderr (True), cut into lines."""
        self._lines_lock = threading.Lock()

    def on_mount(self) -> None:
        self.border_title = "Events"
        self.app.begin_capture_print(self)

    def post_message(self, message: Message) -> bool:
        """What is printed in the platform's process (the processor's ``print()``, in either isolation) comes here
        from the printing thread, a ``Print`` message per write: it is cut into lines and held to a
        :class:`LineBudget` there, so a flood queues no more than the budget's lines on the loop (each write
        queued, a processor printing faster than the dashboard draws grew the queue without bound)."""
        if not isinstance(message, events.Print):
            return super().post_message(message)
        with self._lines_lock:
            lines = self._lines[message.stderr].feed(message.text)
        self._printed.lines([(message.stderr, line) for line in lines if line.strip()])
        return True

    def on_event_log_view_printed(self, message: Printed) -> None:
        if message.left_out:
            self._write(time.time(), f"! {message.left_out} more printed lines not shown (too many at once)",
                        self.get_component_rich_style("log--warning"))
        else:
            self._write(time.time(), f"  {message.line}")

    def add_event(self, event: Event) -> None:
        """Append one event."""
        style = self.get_component_rich_style(f"log--{event.level}") if event.level != "info" else None
        origin = f"[{event.origin}] " if event.origin not in ("platform", "tui") else ""
        self._write(event.t_wall_ns / 1e9, f"{LEVEL_MARK[event.level]} {event.kind}: {origin}{event.message}", style)

    def _write(self, t_wall_s: float, text: str, style: Style | None = None) -> None:
        line = Text(time.strftime("%H:%M:%S ", time.localtime(t_wall_s)), self.get_component_rich_style("log--time"))
        line.append(text, style)
        self.write(line)


def _printed_line(stderr: bool, line: str) -> str:
    return ("stderr: " if stderr else "print: ") + safe(shorten(line, PRINT_CHARS))
