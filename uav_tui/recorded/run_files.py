"""Reading a run's files whatever state they are in: what can be read is, and each problem is one line.

A run is written by a drone that may lose power, fill its card or be copied off half-way: ``run.json``
may not parse, a CSV may be empty, cut in the middle of a row, hold NUL or binary bytes, have rows
with too many fields or text in a number column. :func:`read_json` and :func:`read_table` never
raise on such content; they return what they could read and a list of :class:`Problem`, each naming
the file, the line and what is wrong (at most one per file and kind, with how many more there were).
"""

from __future__ import annotations

import csv
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

_FLAG = {"true": True, "1": True, "false": False, "0": False}
"""How a flag may be spelt (the recorder writes True / False)."""


@dataclass(frozen=True)
class Problem:
    """Something wrong in one of a run's files, and what was done about it."""

    path: Path
    line: int | None
    """1-based line of the file (None: the whole file)."""
    what: str

    def __str__(self) -> str:
        return f"{self.path}{f' line {self.line}' if self.line else ''}: {self.what}"


class _Problems:
    """Collects problems, one per (kind) with the count of the others of that kind."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.first: dict[str, tuple[int | None, str]] = {}
        self.more: dict[str, int] = {}

    def add(self, kind: str, line: int | None, what: str) -> None:
        if kind in self.first:
            self.more[kind] = self.more.get(kind, 0) + 1
        else:
            self.first[kind] = (line, what)

    def done(self) -> list[Problem]:
        return [Problem(self.path, line, what + (f" (and {self.more[kind]} more such)" if kind in self.more else ""))
                for kind, (line, what) in self.first.items()]


def read_json(path: Path) -> tuple[dict[str, Any], list[Problem]]:
    """``run.json`` as a dict; an empty one and the problem when it cannot be read."""
    try:
        text = path.read_bytes().decode("utf-8", errors="replace")
    except OSError as exc:
        return {}, [Problem(path, None, f"cannot be read: {exc.strerror or exc}")]
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        return {}, [Problem(path, exc.lineno, f"not valid JSON ({exc.msg}, column {exc.colno}); the run's settings "
                            "are unknown")]
    if not isinstance(data, dict):
        return {}, [Problem(path, 1, f"holds a JSON {type(data).__name__}, not an object; the run's settings are "
                            "unknown")]
    return data, []


def read_table(path: Path, columns: Sequence[str], dtype_of: Callable[[str], str]) -> tuple[pd.DataFrame,
                                                                                          list[Problem]]:
    """A CSV as a DataFrame with ``dtype_of(column)`` per column; ``columns`` are what this version writes.

    A missing header (the first line is data) is read with ``columns``; rows with another number of
    fields than the header are left out; cells that do not convert are left empty; NUL bytes and bytes
    that are not UTF-8 are replaced. Each kind of problem is reported once, at its first line.
    """
    problems = _Problems(path)
    header, rows, lines = _rows(path, columns, problems)
    cells = dict(zip(header, map(list, zip(*rows, strict=True)), strict=False)) if rows else {}
    names = list(dict.fromkeys([*header, *columns]))
    converted = {name: _convert(cells.get(name) or [""] * len(rows), dtype_of(name), name, lines, problems)
                 for name in names}
    return pd.DataFrame(converted, index=pd.RangeIndex(len(rows))), problems.done()


def _rows(path: Path, columns: Sequence[str], problems: _Problems) -> tuple[list[str], list[list[str]], list[int]]:
    """(header, rows with as many fields as the header, the line each row is on)."""
    if not path.is_file():
        return list(columns), [], []
    try:
        data = path.read_bytes()
    except OSError as exc:
        problems.add("read", None, f"cannot be read: {exc.strerror or exc}")
        return list(columns), [], []
    if b"\0" in data:
        problems.add("nul", data[: data.index(b"\0")].count(b"\n") + 1, "NUL bytes (left out)")
        data = data.replace(b"\0", b"")
    text = data.decode("utf-8", errors="replace")
    if "\ufffd" in text:
        problems.add("utf8", text[: text.index("\ufffd")].count("\n") + 1, "bytes that are not UTF-8 text (read as "
                     "\ufffd)")
    if not text.strip():
        problems.add("empty", None, "empty, not even a header line")
        return list(columns), [], []
    reader = csv.reader(text.splitlines())
    header = next(reader)
    if not set(header) & set(columns):  # data where the header should be
        problems.add("header", 1, f"no header line (the first line is data): read as the {len(columns)} columns this "
                     "version writes")
        reader = csv.reader(text.splitlines())
        header = list(columns)
    elif len(set(header)) != len(header):
        problems.add("header", 1, "a column name twice in the header: the later one is left out")
    width = len(header)
    keep = [i for i, name in enumerate(header) if name not in header[:i]]  # a name given twice: its first column
    rows, lines = [], []
    for row in reader:
        if len(row) == width:
            rows.append([row[i] for i in keep])
            lines.append(reader.line_num)
        elif row:
            problems.add("ragged", reader.line_num, f"{len(row)} fields where the header has {width} (row left out)")
    header = [header[i] or f"column_{i + 1}" for i in keep]
    return header, rows, lines


def _convert(text: list[str], dtype: str, name: str, lines: list[int], problems: _Problems) -> pd.Series:
    """One column's cells as ``dtype``; cells that do not convert are left empty and reported."""
    empty = np.array([not value for value in text], bool)
    if dtype == "string":
        return pd.Series(pd.array([value or None for value in text], dtype="string"))
    if dtype == "boolean":
        flags = [_FLAG.get(value.lower()) for value in text]
        _report(text, empty | np.array([f is not None for f in flags], bool), name, "not True or False", lines,
                problems)
        return pd.Series(pd.array(flags, dtype="boolean"))
    if dtype == "Int64":
        try:  # all whole numbers (the usual case): parsed in one go, nanoseconds exact
            values = np.array([value or "0" for value in text], dtype=str).astype(np.int64)
            return pd.Series(pd.arrays.IntegerArray(values, empty.copy()))
        except (ValueError, OverflowError):
            parsed = [_int(value) for value in text]
        _report(text, empty | np.array([v is not None for v in parsed], bool), name, "not a whole number", lines,
                problems)
        return pd.Series(pd.array(parsed, dtype="Int64"))
    try:
        return pd.Series(np.array([value or "nan" for value in text], dtype=str).astype(np.float64))
    except ValueError:
        numbers = pd.to_numeric(pd.Series([value or None for value in text], dtype=object), errors="coerce")
    _report(text, empty | numbers.notna().to_numpy(), name, "not a number", lines, problems)
    return numbers.astype(np.float64)


def _int(text: str) -> int | None:
    try:
        return int(text)
    except ValueError:
        try:
            value = float(text)
        except ValueError:
            return None
        return int(value) if math.isfinite(value) and value.is_integer() else None


def _report(text: list[str], good: np.ndarray, name: str, what: str, lines: list[int], problems: _Problems) -> None:
    """One problem for the first cell that is not ``good``, counting the others."""
    bad = np.flatnonzero(~good)
    if len(bad):
        problems.add(what, lines[bad[0]], f"column {name}: {text[bad[0]][:40]!r} is {what} (left empty)")
        if len(bad) > 1:
            problems.more[what] = problems.more.get(what, 0) + len(bad) - 1
