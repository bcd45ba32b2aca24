"""The summary's lines on what happened in a run: its warnings and errors, listed, and its precision landing (the
landing targets sent or not, and where it touched down)."""

from __future__ import annotations

import math
import re

import numpy as np
import pandas as pd

from uav_tui.output.text import shorten

MAX_LISTED = 20
"""At most this many warnings and errors are listed (the first ones: what followed often follows from them)."""

MESSAGE_CHARS = 200
"""A longer listed message is cut (events.csv has it whole)."""

MAX_REASONS = 3
"""The most frequent reasons a landing target was not sent that are named."""


def executed_count(frames: pd.DataFrame) -> int:
    """Frames whose vector was flown: decided ``executed``, also ``executed (clamped ...)`` (as the track's arrows
    count them)."""
    return int(frames["decision"].fillna("").astype(str).str.startswith("executed").sum())


def problem_lines(events: pd.DataFrame) -> list[str]:
    """``  12.3 s warning link: ...`` for the first :data:`MAX_LISTED` warnings and errors, then how many more."""
    problems = events[events["level"].isin(("warning", "error"))]
    lines = [f"  {t:.1f} s {level} {kind}: {shorten(_one_line(str(message)), MESSAGE_CHARS)}"
             for t, level, kind, message in problems[["t_s", "level", "kind", "message"]].head(MAX_LISTED)
             .itertuples(index=False)]
    if len(problems) > MAX_LISTED:
        lines.append(f"  ... and {len(problems) - MAX_LISTED} more (events.csv has them all)")
    return lines


def _one_line(message: str) -> str:
    """A message of several lines (a traceback) as its first and last: ``frame 9: Traceback ... ValueError: bad``."""
    lines = [line.strip() for line in re.split(r"\n|\\n", message) if line.strip()]
    return " ... ".join(dict.fromkeys((lines[0], lines[-1]))) if lines else ""


def landing_lines(frames: pd.DataFrame, telemetry: pd.DataFrame, pad: pd.DataFrame) -> list[str]:
    """The landing targets sent and not sent (with the commonest reasons), and the touchdown: where, from home and
    from the pad (the median of ``pad``'s ``north_m``/``east_m``, the processor's geo-located target, when it has
    any). Nothing for a run whose processor reported no landing target."""
    landing = frames["landing"].dropna().astype(str) if "landing" in frames else pd.Series(dtype=str)
    landing = landing[landing != ""]
    if landing.empty:
        return []
    sent = int((landing == "sent").sum())
    refused = landing[landing != "sent"].str.removeprefix("not sent: ")
    line = f"landing targets: {sent} sent, {len(refused)} not sent"
    if len(refused):
        reasons = refused.value_counts().head(MAX_REASONS)
        line += " (" + "; ".join(f"{shorten(reason, 80)}: {count}" for reason, count in reasons.items()) + ")"
    lines = [line]
    if (touchdown := _touchdown(telemetry)) is not None:
        t_s, north, east = touchdown
        where = f"touched down at {t_s:.1f} s, N {north:.2f} E {east:.2f} m from home"
        if len(pad):
            pad_north, pad_east = float(pad["north_m"].median()), float(pad["east_m"].median())
            where += (f", {math.hypot(north - pad_north, east - pad_east):.2f} m from the pad (seen at N "
                      f"{pad_north:.2f} E {pad_east:.2f})")
        lines.append(where)
    return lines


def _touchdown(telemetry: pd.DataFrame) -> tuple[float, float, float] | None:
    """``(t_s, north_m, east_m)`` of the last sample on the ground after one in the air, or None."""
    rows = telemetry[["t_s", "in_air", "north_m", "east_m"]].dropna()
    if rows.empty:
        return None
    in_air = rows["in_air"].astype(bool).to_numpy()
    landed = np.flatnonzero(in_air[:-1] & ~in_air[1:]) + 1
    if not len(landed):
        return None
    row = rows.iloc[landed[-1]]
    return float(row["t_s"]), float(row["north_m"]), float(row["east_m"])
