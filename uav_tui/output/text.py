"""Text from outside (network, files, the researcher's code) made safe to print, log and record.

Small functions, applied where text leaves the platform (the event log, the logging formatter,
the CSV writer, ``run.json``, the headless terminal):

- :func:`escape` shows control characters as escapes (``\\x1b``, ``\\n``), so nothing from outside
  can move the cursor, clear the screen or start a line of its own;
- :func:`redact` (from :mod:`sources.uri`, the one redaction function) hides passwords in URIs
  (``rtsp://admin:***@host``) and secret query parameters (``?pwd=***``);
- :func:`describe` renders any untrusted value (a vector of a million numbers, say) in at most N
  characters, escaped; :func:`shorten` cuts long text (a processor's exception message), :func:`last_line`
  takes a traceback's exception line;
- :class:`SafeFormatter` applies them to every log record on the terminal.
"""

from __future__ import annotations

import logging
import re
import reprlib
from typing import Any

from sources.uri import redact

__all__ = ["DESCRIBE_CHARS", "SafeFormatter", "describe", "escape", "last_line", "redact", "safe", "shorten"]

DESCRIBE_CHARS = 80
"""The longest description of an untrusted value."""

_CONTROL = re.compile("[\x00-\x1f\x7f-\x9f\u061c\u200e\u200f\u2028\u2029\u202a-\u202e\u2066-\u2069]")
"""C0/C1 controls, DEL, Unicode line breaks and the invisible characters that reorder text on screen."""
_SHORT = reprlib.Repr()  # keyword arguments need Python 3.12
_SHORT.maxlevel, _SHORT.maxstring, _SHORT.maxlong, _SHORT.maxother = 2, DESCRIBE_CHARS, 24, DESCRIBE_CHARS
_SHORT.maxtuple = _SHORT.maxlist = _SHORT.maxdict = _SHORT.maxset = _SHORT.maxfrozenset = _SHORT.maxdeque = 4


def escape(text: str, *, multiline: bool = False) -> str:
    """``text`` with every control character shown as its escape (``\\x1b``, ``\\n``, ``\\u202e``).

    Args:
        text: anything; non-strings are converted with ``str``.
        multiline: keep line breaks (a traceback), but indent every line after the first by two
            spaces, so no line can pass for one the platform printed itself.
    """
    text = text if isinstance(text, str) else str(text)
    if multiline:
        return "\n  ".join(escape(line) for line in text.splitlines() or [""])
    if not _CONTROL.search(text):
        return text
    return _CONTROL.sub(_escape_one, text)


def safe(text: str, *, multiline: bool = False) -> str:
    """:func:`redact` then :func:`escape`: what every boundary applies to outside text."""
    return escape(redact(text if isinstance(text, str) else str(text)), multiline=multiline)


def last_line(text: str) -> str:
    """The last line of a traceback: its exception. Only ``\n`` ends a line here; a ``\r`` or ``\x85`` inside the
    exception's message is part of it (``str.splitlines`` would show what follows it as the whole message)."""
    return text.strip().rsplit("\n", 1)[-1]


def shorten(text: str, limit: int) -> str:
    """``text`` cut to ``limit`` characters, saying how many were left out."""
    return text if len(text) <= limit else f"{text[:limit]}... ({len(text) - limit} more characters)"


def describe(value: Any, limit: int = DESCRIBE_CHARS) -> str:
    """A short, escaped description of any untrusted value, at most ``limit`` characters.

    Containers show their first items and their length (``(1, 2, 3, 4, ...) (1000000 items)``);
    nothing is converted in full, so a huge value costs no more than a small one.
    """
    try:
        text = _SHORT.repr(value)
    except Exception:  # noqa: BLE001 - a broken __repr__ must not break the report about it
        text = f"<{type(value).__name__}>"
    try:
        size = len(value) if isinstance(value, tuple | list | dict | set | frozenset) else None
    except Exception:  # noqa: BLE001
        size = None
    if size is not None and size > 4:
        text += f" ({size} items)"
    text = escape(text)
    return text if len(text) <= limit else text[:max(0, limit - 3)] + "..."


class SafeFormatter(logging.Formatter):
    """Formats log records with :func:`safe`: passwords hidden, the message on one line with control
    characters escaped, a traceback's lines indented: a logged string cannot clear the terminal or
    forge a line."""

    def formatMessage(self, record: logging.LogRecord) -> str:  # noqa: N802 - logging's name
        return safe(super().formatMessage(record))

    def formatException(self, ei: Any) -> str:  # noqa: N802
        return "  " + safe(super().formatException(ei), multiline=True)

    def formatStack(self, stack_info: str) -> str:  # noqa: N802
        return "  " + safe(super().formatStack(stack_info), multiline=True)


def _escape_one(match: re.Match[str]) -> str:
    char = match.group()
    if char in "\n\r\t":
        return {"\n": "\\n", "\r": "\\r", "\t": "\\t"}[char]
    code = ord(char)
    return f"\\x{code:02x}" if code <= 0xFF else f"\\u{code:04x}"
