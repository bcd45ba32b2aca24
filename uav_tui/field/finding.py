"""What one ``uav-tui doctor`` check found: OK, WARN (flyable, but fix it) or FAIL (blocks flight), and what to do."""

from __future__ import annotations

import enum
from dataclasses import dataclass


class Level(enum.IntEnum):
    """How bad a finding is; the worst one decides ``doctor``'s exit status."""

    OK = 0
    WARN = 1
    FAIL = 2


@dataclass(frozen=True, slots=True)
class Finding:
    """One line of ``doctor``'s output: the subject checked, how it stands, and what was found or what to do."""

    subject: str
    level: Level
    text: str

    def line(self) -> str:
        return f"{self.level.name:<4} {self.subject}: {self.text}"


def ok(subject: str, text: str) -> Finding:
    return Finding(subject, Level.OK, text)


def warn(subject: str, text: str) -> Finding:
    return Finding(subject, Level.WARN, text)


def fail(subject: str, text: str) -> Finding:
    return Finding(subject, Level.FAIL, text)
