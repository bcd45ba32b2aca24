"""Darknet's model files read as data: the ``.cfg`` sections and the ``.weights`` floats."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np


@dataclass(frozen=True)
class Section:
    """One ``[kind]`` block of a ``.cfg``: its ``key=value`` lines as strings."""

    kind: str
    options: dict[str, str]

    def get_int(self, key: str, default: int) -> int:
        return int(self.options.get(key, default))

    def get_float(self, key: str, default: float) -> float:
        return float(self.options.get(key, default))

    def get_ints(self, key: str) -> list[int]:
        """A comma-separated list (``layers=-1,80``, ``mask=3,4,5``); empty when the key is absent."""
        return [int(v) for v in self.options.get(key, "").split(",") if v.strip()]

    def get(self, key: str, default: str) -> str:
        return self.options.get(key, default)


def read_cfg(path: Path) -> list[Section]:
    """The sections in file order, ``[net]`` first; ``#`` and ``;`` start comments.

    Raises:
        ValueError: a line before the first section, or a line that is not ``key=value``.
    """
    sections: list[Section] = []
    for number, raw in enumerate(path.read_text().splitlines(), 1):
        line = raw.split("#", 1)[0].split(";", 1)[0].strip()
        if not line:
            continue
        if line.startswith("[") and line.endswith("]"):
            sections.append(Section(line[1:-1].strip(), {}))
        elif "=" in line and sections:
            key, value = line.split("=", 1)
            sections[-1].options[key.strip()] = value.strip()
        else:
            raise ValueError(f"{path.name}:{number}: expected [section] or key=value, got {raw!r}")
    if not sections or sections[0].kind not in ("net", "network"):
        raise ValueError(f"{path.name}: the first section must be [net]")
    return sections


class Weights:
    """The ``.weights`` floats after the header, taken in the order the layers read them."""

    def __init__(self, path: Path) -> None:
        major, minor, _revision = np.fromfile(path, np.int32, 3)
        # "images seen" is 64-bit from format 0.2 on (Darknet's load_weights)
        header = 3 * 4 + (8 if major * 10 + minor >= 2 else 4)
        self._values = np.fromfile(path, np.float32, offset=header)
        self._at = 0
        self._name = path.name

    def take(self, count: int) -> np.ndarray:
        """The next ``count`` floats.

        Raises:
            ValueError: the file ends first (it is not the ``.cfg``'s model).
        """
        if self._at + count > len(self._values):
            raise ValueError(f"{self._name} ends before the .cfg's layers do: is it the weights of this .cfg?")
        out = self._values[self._at : self._at + count]
        self._at += count
        return out

    def check_used_up(self) -> None:
        """Raises ValueError when floats are left over (the weights of another ``.cfg``)."""
        if self._at != len(self._values):
            raise ValueError(f"{self._name} has {len(self._values) - self._at} floats the .cfg's layers do not use")
