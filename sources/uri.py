"""Parsing of camera URIs such as ``file:flight.mp4?realtime=0`` or ``usb:/dev/video2?width=1280``."""

from __future__ import annotations

from dataclasses import dataclass, field
from urllib.parse import parse_qsl, urlsplit, urlunsplit

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


def redact(url: str) -> str:
    """``url`` with any password replaced by ``***``."""
    parts = urlsplit(url)
    if parts.password is None:
        return url
    host = parts.hostname or ""
    netloc = f"{parts.username}:***@{host}" + (f":{parts.port}" if parts.port else "")
    return urlunsplit(parts._replace(netloc=netloc))
