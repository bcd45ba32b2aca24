"""The run's CSV tables on disk, appended in whole lines only.

Rows are collected in memory and appended with one ``write`` per file; a failed or short write is cut back to the
last whole line, so a process killed with SIGKILL leaves valid CSV up to its last append.
"""

from __future__ import annotations

import contextlib
import csv
import io
import os
from collections.abc import Callable, Iterator, Mapping, Sequence
from pathlib import Path
from typing import Any

from uav_tui.output.text import safe


class CsvFiles:
    """One ``<table>.csv`` per table in ``run_dir``, each created with its header on the first append.

    Used from one thread (the disk writer's).

    Args:
        run_dir: the run folder (exists).
        tables: table name -> column names.
        write: one ``os.write(fd, data)``, returning how much was written (the disk writer's seam).
    """

    def __init__(self, run_dir: Path, tables: Mapping[str, Sequence[str]], write: Callable[[int, bytes], int]) -> None:
        self.run_dir = run_dir
        self.tables = {name: list(columns) for name, columns in tables.items()}
        self.rows_written = dict.fromkeys(tables, 0)
        """Rows on disk per table."""
        self._write = write
        self._pending: dict[str, list[list[Any]]] = {name: [] for name in tables}
        self._files: dict[str, tuple[int, int]] = {}  # table -> (fd, size)

    def add(self, table: str, values: list[Any]) -> None:
        """Collect one row for the next append."""
        self._pending[table].append(values)

    def take_pending(self) -> Iterator[tuple[str, list[list[Any]]]]:
        """Each table's collected rows, taken out of the collection (tables without rows are skipped)."""
        for table, rows in self._pending.items():
            if rows:
                self._pending[table] = []
                yield table, rows

    def append(self, table: str, rows: list[list[Any]]) -> int:
        """Append ``rows`` to ``table``'s file in whole lines; returns the bytes written.

        Raises:
            OSError: the file could not be opened or written; what reached it was cut back to the last whole line.
        """
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        if table not in self._files:
            writer.writerow(self.tables[table])
        # Text from outside (processor strings, paths, messages) reaches the file redacted and escaped.
        writer.writerows([safe(v) if isinstance(v, str) else v for v in row] for row in rows)
        data = buffer.getvalue().encode()
        fd, size = self._files.get(table) or (self._open(table), 0)
        self._files[table] = (fd, size)
        written = 0
        try:
            while written < len(data):
                written += self._write(fd, data[written:])
        except OSError:
            with contextlib.suppress(OSError):
                os.ftruncate(fd, size)  # cut back to the last whole line
                os.lseek(fd, size, os.SEEK_SET)
            if size == 0:  # not even the header made it: write it again next time
                del self._files[table]
                os.close(fd)
            raise
        self._files[table] = (fd, size + written)
        self.rows_written[table] += len(rows)
        return written

    def close(self) -> None:
        """Close every file."""
        for fd, _ in self._files.values():
            os.close(fd)
        self._files.clear()

    def _open(self, table: str) -> int:
        return os.open(self.run_dir / f"{table}.csv", os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o644)
