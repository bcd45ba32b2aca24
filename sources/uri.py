"""Parsing of camera URIs such as ``file:flight.mp4?realtime=0`` or ``usb:/dev/video2?width=1280``, and
:func:`redact`, the one function that hides the credentials in URIs wherever they are shown or recorded."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from urllib.parse import parse_qsl

from sources.errors import SourceUriError

_TRUE = {"1", "true", "yes", "on"}
_FALSE = {"0", "false", "no", "off"}


@dataclass
class SourceUri:
    """A camera URI split into scheme, target and query parameters.

    Sources take their options with the ``take_*`` methods; :meth:`finish` then rejects any
    parameter nobody took, so a typo (``?widht=640``) is an error that names it.
    """

    text: str
    scheme: str
    target: str
    params: dict[str, str] = field(default_factory=dict)

    @classmethod
    def parse(cls, text: str) -> SourceUri:
        """Split ``text``; raises SourceUriError when it has no scheme."""
        text = text.strip()
        scheme, sep, rest = text.partition(":")
        if not sep or not scheme.isidentifier():
            raise SourceUriError(
                f"camera URI {text!r} has no scheme: use file:PATH, synthetic:, usb:0, picam:0, "
                "rtsp://HOST/PATH or sim:",
                key="source",
            )
        if rest.startswith("//"):  # a network URL: the whole URL is the target, its query stays with it
            return cls(text, scheme.lower(), text)
        target, _, query = rest.partition("?")
        return cls(text, scheme.lower(), target, dict(parse_qsl(query, keep_blank_values=True)))

    def take_str(self, name: str, default: str | None = None) -> str | None:
        return self.params.pop(name, default)

    def take_int(self, name: str, default: int | None = None) -> int | None:
        value = self.params.pop(name, None)
        if value is None:
            return default
        try:
            number = int(value)
        except ValueError:
            raise self._bad(name, value, "a whole number") from None
        if number < 0:
            raise self._bad(name, value, "a number >= 0")
        return number

    def take_float(self, name: str, default: float | None = None) -> float | None:
        value = self.params.pop(name, None)
        if value is None:
            return default
        try:
            number = float(value)
        except ValueError:
            raise self._bad(name, value, "a number") from None
        if not number >= 0:
            raise self._bad(name, value, "a number >= 0")
        return number

    def take_bool(self, name: str, default: bool) -> bool:
        value = self.params.pop(name, None)
        if value is None:
            return default
        if value.lower() in _TRUE:
            return True
        if value.lower() in _FALSE:
            return False
        raise self._bad(name, value, "1 or 0")

    def finish(self) -> None:
        """Raise SourceUriError if a parameter was given that the source does not understand."""
        if self.params:
            names = ", ".join(sorted(self.params))
            raise SourceUriError(f"camera URI {self.text!r}: unknown parameter(s) {names}", key="source")

    def _bad(self, name: str, value: str, expected: str) -> SourceUriError:
        return SourceUriError(f"camera URI {self.text!r}: {name}={value!r} must be {expected}", key="source")


SECRET_PARAMETERS = ("password", "passwd", "pass", "pwd", "pw", "token", "auth", "authorization", "key", "apikey",
                     "secret", "signature", "sig", "credential", "credentials", "session", "sessionid")
"""Query parameters whose value is hidden, also after a prefix (``access_token``, ``api_key``, ``x-auth``)."""

_URI_START = re.compile(r"\b[a-zA-Z][a-zA-Z0-9+.-]{0,31}://")
"""A scheme (bounded: an unbounded one made a long run of letters and dots quadratic)."""
_URI_END = re.compile(r"[\s\"'<>]")
"""Where a URI ends in text (a space, a quote in JSON, a bracket in HTML), unless its password holds one."""
_HOST = r"(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._~%-]+)(?::\d*)?"
"""A host (name, IPv4 or [IPv6]) and a port."""
_HOST_AFTER = re.compile(_HOST + r"(?:[/?#]|$)")
"""What follows the ``@`` that ends a password: a host, a port, then the path or the end."""
_PORT_THEN_TEXT = re.compile(r"(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._~%-]*):\d*(?:[/?#].*|[^\w@]*)", re.DOTALL)
"""A host (or none: ``udp://:14540``) and a port, then a path or punctuation: cut by a space, no password."""
_HOST_THEN_PATH = re.compile(_HOST + r"[/?#]")
_AT_HOST = re.compile("@(?=" + _HOST + r"(?:[/?#\s\"'<>]|$))")
"""An ``@`` a host follows, then the path or the end of the URI."""
_NO_FURTHER = re.compile(r'\n|://|(?<!\\)(?:\\\\)*"\s*[,:}\]]')
"""What a password never reaches over: the line's end, another URI, the end of a JSON string (``", "key"``)."""
_SECRET_VALUE = re.compile(
    r"(?P<name>[?&;#](?:[\w.-]*?[_.-])?(?:" + "|".join(sorted(SECRET_PARAMETERS, key=len, reverse=True)) +
    r")=)[^&;#\s\"'<>]+", re.IGNORECASE)


def redact(text: str) -> str:
    """``text`` with the password of every URI in it and the value of every secret parameter replaced by ``***``.

    A password may hold any character, ``/``, ``@``, ``#``, ``?``, a space, a quote or a bracket included
    (``rtsp://admin:P@ss/#1@host/``, ``rtsp://admin:pa ss@host``): it runs from the first ``:`` after the user name
    to the last ``@`` that a host name follows, so a path or query holding an ``@`` is hidden with it rather than a
    part of a password shown. Parameters named in :data:`SECRET_PARAMETERS` (``?pwd=``, ``&token=``,
    ``;password=``, ``?api_key=``, ``#access_token=``) keep their name only.
    """
    if "://" in text and "@" in text:
        text = _hide_passwords(text)
    if "=" in text:
        text = _SECRET_VALUE.sub(r"\g<name>***", text)
    return text


def _hide_passwords(text: str) -> str:
    parts, done = [], 0
    for match in _URI_START.finditer(text):
        start = match.end()
        if start <= done:  # a scheme inside a URI already handled
            continue
        end = _uri_end(text, start)
        parts += [text[done:start], _without_password(text[start:end])]
        done = end
    return "".join([*parts, text[done:]])


def _uri_end(text: str, start: int) -> int:
    """Where the URI whose ``scheme://`` ends at ``start`` ends in ``text``: at the first space, quote or bracket,
    or, when that cuts a password (``rtsp://admin:pa ss@cam``), after the first host that an ``@`` further on the
    same line and JSON string precedes."""
    end_match = _URI_END.search(text, start)
    end = end_match.start() if end_match else len(text)
    first = text[start:end]
    colon = first.find(":")
    if end == len(text) or colon < 0 or any(c in first[:colon] for c in "/?#"):
        return end  # the whole text, or no password
    if "@" not in first and (_HOST_AFTER.match(first) or _PORT_THEN_TEXT.fullmatch(first)):
        return end  # host:port and a path, or punctuation
    if any(_HOST_THEN_PATH.match(first, i + 1) for i in range(colon, len(first)) if first[i] == "@"):
        return end  # user:password@host/path
    further = _NO_FURTHER.search(text, start)  # from the start: the cut may be a JSON string's end (``\\"``)
    at = _AT_HOST.search(text, end, further.start() if further else len(text))
    if at is None:
        return end
    end_match = _URI_END.search(text, at.end())
    return end_match.start() if end_match else len(text)


def _without_password(rest: str) -> str:
    """``user:***@host/path`` for ``rest``, a URI after its ``scheme://``; ``rest`` itself when it has no password."""
    colon = rest.find(":")
    at = rest.find("@", colon + 1)
    if colon < 0 or at < 0 or any(c in rest[:colon] for c in "/?#"):
        return rest
    if 0 <= rest.find("?") < at and rest[colon + 1:_first(rest, "/?#", colon)].isdigit():
        return rest  # host:port, and the @ is in the query
    ats = [i for i in range(at, len(rest)) if rest[i] == "@"]
    host = next((i for i in reversed(ats) if _HOST_AFTER.match(rest, i + 1)), ats[-1])
    return rest[:colon] + ":***@" + rest[host + 1:]


def _first(text: str, chars: str, start: int) -> int:
    """Where the first of ``chars`` is in ``text`` from ``start`` on (``len(text)`` when none is)."""
    return min((i for i in (text.find(c, start) for c in chars) if i >= 0), default=len(text))
