"""The error loading a processor raises; it names the file, the class and what is missing."""

from __future__ import annotations


class ProcessorLoadError(Exception):
    """A processor cannot be loaded (a configuration error: ``key`` is ``processor``).

    Attributes:
        path: the file (or module) the processor came from, when known.
        class_name: the class that was asked for.
        missing: what is missing (a module, a class, a required method), when that is the cause.
    """

    key = "processor"

    def __init__(
        self,
        message: str,
        *,
        path: str | None = None,
        class_name: str | None = None,
        missing: str | None = None,
    ) -> None:
        super().__init__(message)
        self.path = path
        self.class_name = class_name
        self.missing = missing
