"""The key bar: every active key binding, wrapped over as many lines as the terminal needs.

Textual's ``Footer`` is one line, which cuts off half the keys at 80 columns; an operator must see
quit and hold as surely as arm. Keys that cannot apply now are dimmed; clicking a key runs it.
"""

from __future__ import annotations

from itertools import groupby
from typing import ClassVar

from rich.text import Text
from textual.binding import Binding
from textual.widgets import Static

KEY_NAMES = {"question_mark": "?", "colon": ":", "enter": "Enter", "escape": "Esc", "left": "\u2190", "up": "\u2191",
             "right": "\u2192", "down": "\u2193"}
"""Short names for keys whose Textual name is long."""


def key_name(binding: Binding) -> str:
    key = binding.key.split(",")[0]
    return KEY_NAMES.get(key, key.upper() if key.startswith("f") and key[1:].isdigit() else key)


def _keys_label(bindings: list[Binding]) -> str:
    names = [key_name(binding) for binding in bindings]
    if len(names) > 2 and all(name.startswith("F") for name in names):
        return f"{names[0]}-{names[-1]}"
    return "".join(names) if all(len(name) == 1 for name in names) else "/".join(names)


class KeyBar(Static):
    """Shows the screen's active bindings (``show=True``) as ``key Label`` pairs; grouped keys share a label."""

    COMPONENT_CLASSES: ClassVar[set[str]] = {"keybar--key", "keybar--label"}
    DEFAULT_CSS = """
    KeyBar {
        dock: bottom; height: auto; max-height: 3; background: $footer-background; padding: 0 1;
        link-style: none; link-background-hover: $block-hover-background; link-style-hover: none;
        & > .keybar--key { color: $footer-key-foreground; background: $footer-key-background; text-style: bold; }
        & > .keybar--label { color: $footer-description-foreground; }
    }
    """

    def on_mount(self) -> None:
        self.screen.bindings_updated_signal.subscribe(self, lambda _screen: self.redraw())
        self.redraw()

    def on_resize(self) -> None:
        self.redraw()

    def redraw(self) -> None:
        """Rebuild the text from the screen's bindings (called when they or the width change)."""
        shown = [(binding, enabled) for _node, binding, enabled, _tip in self.screen.active_bindings.values()
                 if binding.show]
        key_style = self.get_component_rich_style("keybar--key")
        label_style = self.get_component_rich_style("keybar--label")
        width = self.content_size.width or self.app.size.width - 2
        text, line_length = Text(no_wrap=True), 0
        for group, members in groupby(shown, key=lambda item: item[0].group or item[0].key):
            items = list(members)
            first, enabled = items[0]
            label = group.description if isinstance(group, Binding.Group) else first.description
            item = Text.assemble((_keys_label([binding for binding, _ in items]), key_style), " ",
                                 (label, label_style))
            if not enabled:
                item.stylize("dim")
            item.apply_meta({"@click": f"app.simulate_key({first.key!r})"})
            if line_length and line_length + 2 + item.cell_len > width:  # a key and its label stay together
                text.append("\n")
                line_length = 0
            elif line_length:
                text.append("  ")
                line_length += 2
            text.append_text(item)
            line_length += item.cell_len
        self.update(text)
