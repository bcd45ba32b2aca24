"""Type any operator command (``takeoff 8``, ``orbit 5 1``, ``source usb:1``), as in a ``--script`` file."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Vertical
from textual.screen import ModalScreen
from textual.widgets import Input, Label

from uav_tui.flight.commands import COMMANDS


class CommandPrompt(ModalScreen[str]):
    """One line of input; Enter sends it (dismisses with the text), Escape dismisses with ""."""

    DEFAULT_CSS = """
    CommandPrompt { align: center bottom; }
    CommandPrompt > Vertical {
        width: 100%; height: auto; padding: 0 1; background: $surface; border-top: solid $primary;
    }
    CommandPrompt Label { color: $text-muted; width: 1fr; }
    """

    BINDINGS = [Binding("escape", "cancel", "Cancel")]

    def compose(self) -> ComposeResult:
        with Vertical():
            yield Label("commands: " + " ".join(word for word in COMMANDS if word != "wait"))
            yield Input(placeholder="command, e.g. takeoff 8   (Enter sends, Esc cancels)")

    def on_input_submitted(self, event: Input.Submitted) -> None:
        self.dismiss(event.value.strip())

    def action_cancel(self) -> None:
        self.dismiss("")
