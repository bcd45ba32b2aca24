"""The line budget: a burst, then a steady rate, and the count of what was left out said in time."""

from __future__ import annotations

import asyncio
import threading

import pytest

from uav_tui.output.line_budget import LineBudget, LineSplitter


async def test_a_steady_stream_at_the_rate_does_not_starve_the_count() -> None:
    said: list[str] = []
    budget = LineBudget(said.append, lambda n: said.append(f"{n} left out"), burst=2, per_s=20.0)
    for n in range(10):  # a flood: 2 shown, 8 left out
        budget.line(f"flood {n}")
    for n in range(12):  # then one line per refill, for 0.6 s
        await asyncio.sleep(0.05)
        budget.line(f"steady {n}")
    # Before: each steady line took the token the count waited for, so the count came only at close.
    assert said[:3] == ["flood 0", "flood 1", "8 left out"]
    budget.close()
    assert sum("left out" in line for line in said) <= 1 + sum(line.startswith("steady") for line in said)


async def test_a_flood_from_another_thread_costs_a_count_said_on_the_loop() -> None:
    said: list[str] = []
    counted_on: list[int] = []

    def left_out(count: int) -> None:
        said.append(f"{count} left out")
        counted_on.append(threading.get_ident())

    budget = LineBudget(said.append, left_out, burst=3, per_s=10.0)
    reader = threading.Thread(target=budget.lines, args=([f"line {n}" for n in range(100_000)],))
    reader.start()
    reader.join()
    assert said == ["line 0", "line 1", "line 2"]
    await asyncio.sleep(0.3)  # the count is said 1 / per_s after the first line left out, by the loop
    assert said[3:] == ["99997 left out"] and counted_on == [threading.get_ident()]


@pytest.mark.parametrize("newline", ["\n", b"\n"])
def test_the_splitter_ends_lines_at_newline_only_and_cuts_one_that_never_ends(newline: str | bytes) -> None:
    """The one splitter of the processor's prints, the TUI's captured prints and native libraries' stderr."""
    def text(value: str) -> str | bytes:
        return value if isinstance(newline, str) else value.encode()

    lines = LineSplitter(newline, 8)
    assert lines.feed(text("ab")) == [] and lines.feed(text("c\rd\nef")) == [text("abc\rd")]  # \r is in its line
    assert lines.feed(text("ghij")) == []  # 6 of 8
    assert lines.feed(text("kl")) == [text("efghijkl")]  # reached 8 unfinished: given as it is
    assert lines.feed(text("\n\nxy")) == [text(""), text("")]
    assert lines.rest() == text("xy") and lines.rest() == text("")
