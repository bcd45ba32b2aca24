"""Confirmation of a dangerous action (arm, take-off, disarm, quit while armed)."""

from __future__ import annotations

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Grid
from textual.screen import ModalScreen
from textual.widgets import Button, Label


class ConfirmScreen(ModalScreen[bool]):
    """Asks ``question``; dismisses with True only for ``y`` / the confirm button.

    Escape, ``n`` and the cancel button dismiss with False, so a stray key never confirms.
    """

    DEFAULT_CSS = """
    ConfirmScreen { align: center middle; }
    ConfirmScreen > Grid {
        grid-size: 2; grid-gutter: 1 2; grid-rows: auto 3; padding: 0 1;
        width: 56; max-width: 100%; height: auto; border: thick $warning; background: $surface;
    }
    ConfirmScreen #question { column-span: 2; width: 1fr; content-align: center middle; padding: 1 0 0 0; }
    ConfirmScreen Button { width: 1fr; }
    """

    BINDINGS = [
        Binding("y", "answer(True)", "Yes"),
        Binding("n", "answer(False)", "No"),
        Binding("escape", "answer(False)", "Cancel"),
    ]

    def __init__(self, question: str, confirm_label: str) -> None:
        super().__init__()
        self.question = question
        self.confirm_label = confirm_label

    def compose(self) -> ComposeResult:
        with Grid():
            yield Label(self.question, id="question")
            yield Button(f"{self.confirm_label} (y)", variant="warning", id="yes")
            yield Button("Cancel (n/Esc)", variant="default", id="no")

    def on_mount(self) -> None:
        self.query_one("#no", Button).focus()

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)
