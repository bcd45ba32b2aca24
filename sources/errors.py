"""Errors a camera source raises; the platform catches them with the other levels' errors."""

from __future__ import annotations


class SourceError(Exception):
    """A camera cannot be opened, or it stopped delivering frames."""


class SourceUriError(SourceError, ValueError):
    """A camera URI cannot be parsed or names an unknown scheme (a configuration error: ``key`` is ``source``)."""

    key = "source"

    def __init__(self, message: str, *, key: str = "source") -> None:
        super().__init__(message)
        self.key = key
