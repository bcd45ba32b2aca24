"""Confirmation of a dangerous action (arm, take-off, disarm, quit while armed)."""

from __future__ import annotations

from collections.abc import Callable

from textual.app import ComposeResult
from textual.binding import Binding
from textual.containers import Grid
from textual.screen import ModalScreen
from textual.widgets import Button, Label

REASK_S = 0.5
"""How often a question that follows the live state is asked again."""


class ConfirmScreen(ModalScreen[bool]):
    """Asks ``question`` (a text, or a function asked again as the state it describes changes); dismisses with True
    only for ``y`` / the confirm button.

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

    def __init__(self, question: str | Callable[[], str], confirm_label: str) -> None:
        super().__init__()
        self.question = question
        """The question, or what asks it from the live state (asked again every :data:`REASK_S`)."""
        self.confirm_label = confirm_label

    def compose(self) -> ComposeResult:
        with Grid():
            yield Label(self.asked(), id="question", markup=False)
            yield Button(f"{self.confirm_label} (y)", variant="warning", id="yes")
            yield Button("Cancel (n/Esc)", variant="default", id="no")

    def on_mount(self) -> None:
        self.query_one("#no", Button).focus()
        if callable(self.question):
            self.set_interval(REASK_S, lambda: self.query_one("#question", Label).update(self.asked()))

    def asked(self) -> str:
        """The question as it stands now."""
        return self.question() if callable(self.question) else self.question

    def on_button_pressed(self, event: Button.Pressed) -> None:
        self.dismiss(event.button.id == "yes")

    def action_answer(self, answer: bool) -> None:
        self.dismiss(answer)
