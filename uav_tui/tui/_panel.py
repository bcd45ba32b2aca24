"""The base of the status panels: a titled block that redraws itself from one :class:`CoreStatus`."""

from __future__ import annotations

from collections.abc import Iterable
from typing import ClassVar

from rich.text import Text
from textual.reactive import reactive
from textual.widgets import Static

from uav_tui.status import CoreStatus

MISSING = "-"
"""Shown where a value has not arrived yet."""


def num(value: float | None, spec: str = ".1f", unit: str = "") -> str:
    """``value`` formatted with ``spec`` and ``unit``, or :data:`MISSING`."""
    return MISSING if value is None else f"{value:{spec}}{unit}"


class StatusPanel(Static):
    """A panel showing part of the core's status; subclasses implement :meth:`describe`.

    Rows are ``label value`` lines; values that need attention use the ``panel--warn`` and
    ``panel--bad`` component styles (set in CSS), so colours live in the stylesheet.
    """

    COMPONENT_CLASSES: ClassVar[set[str]] = {"panel--label", "panel--warn", "panel--bad", "panel--good"}
    DEFAULT_CSS = """
    StatusPanel {
        border-top: solid $primary;
        border-title-color: $text-primary;
        border-title-style: bold;
        padding: 0 1;
        height: auto;
        text-wrap: nowrap;
        text-overflow: ellipsis;
        & > .panel--label { color: $text-muted; }
        & > .panel--warn { color: $text-warning; text-style: bold; }
        & > .panel--bad { color: $text-error; text-style: bold; }
        & > .panel--good { color: $text-success; }
    }
    """
    TITLE: ClassVar[str] = ""
    """Shown in the panel's top border."""

    status: reactive[CoreStatus | None] = reactive(None, always_update=True, layout=False, repaint=False)
    """The newest snapshot of the core (None until it has started)."""

    def on_mount(self) -> None:
        self.border_title = self.TITLE
        self.watch_status(self.status)

    def watch_status(self, status: CoreStatus | None) -> None:
        # Panels have fixed heights (app.tcss): no layout pass per refresh, which would cost the loop.
        self.update(self.describe(status) if status is not None else Text("starting...", style="italic"),
                    layout=False)

    def describe(self, status: CoreStatus) -> Text:
        """The panel's text for ``status``."""
        raise NotImplementedError

    def room_before(self, tail: Text | str, labels: Iterable[str], minimum: int) -> int | None:
        """Columns a row's value may give its leading part so that ``tail`` after it stays whole, at least
        ``minimum``; the row's label is the longest of ``labels``. None before the panel has a size."""
        if not self.size.width:
            return None
        return max(minimum, self.size.width - max(map(len, labels)) - 1 - len(tail))

    def rows(self, *rows: tuple[str, Text | str]) -> Text:
        """``label value`` lines with the labels in one column."""
        label_style = self.get_component_rich_style("panel--label")
        width = max(len(label) for label, _ in rows)
        text = Text(no_wrap=True, overflow="ellipsis")
        for index, (label, value) in enumerate(rows):
            if index:
                text.append("\n")
            text.append(f"{label:<{width}} ", label_style)
            text.append(value)
        return text

    def styled(self, value: str, level: str) -> Text:
        """``value`` in the ``panel--<level>`` style (``warn``, ``bad``, ``good``)."""
        return Text(value, self.get_component_rich_style(f"panel--{level}"))
