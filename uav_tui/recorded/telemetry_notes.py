"""What a run's report says about its telemetry's holes: gaps between samples, frames not bracketed by samples."""

from __future__ import annotations

import pandas as pd

from uav_tui.recorded.dataset import Dataset

GAP_S = 2.0
"""A telemetry gap this long or longer is reported (every stream the platform reads comes at 1 Hz or more)."""

MAX_LISTED = 3
"""The longest gaps are listed by their start, at most this many."""


def telemetry_gaps(run: Dataset, at_least_s: float = GAP_S) -> pd.DataFrame:
    """Each gap of at least ``at_least_s`` between consecutive telemetry samples: ``start_s`` (``t_s`` of the sample
    before it) and ``length_s``, longest first."""
    times = run.telemetry["t_s"].dropna().sort_values().to_numpy()
    if len(times) < 2:
        return pd.DataFrame({"start_s": [], "length_s": []})
    gaps = pd.DataFrame({"start_s": times[:-1], "length_s": times[1:] - times[:-1]})
    return gaps[gaps["length_s"] >= at_least_s].sort_values("length_s", ascending=False, kind="stable")


def telemetry_notes(run: Dataset) -> list[str]:
    """Summary lines for telemetry gaps of :data:`GAP_S` or more and for frames whose telemetry is extrapolated."""
    lines = []
    gaps = telemetry_gaps(run)
    if len(gaps):
        listed = ", ".join(f"{row.length_s:.1f} s at {row.start_s:.1f} s" for row in gaps.head(MAX_LISTED).itertuples())
        more = f" and {len(gaps) - MAX_LISTED} more" if len(gaps) > MAX_LISTED else ""
        lines.append(f"telemetry gaps: {len(gaps)} of {GAP_S:g} s or more ({listed}{more}); frames captured in them "
                     "have their telemetry interpolated across the gap or held (see the telemetry column)")
    extrapolated = run.extrapolated
    if len(extrapolated):
        reach = extrapolated["extrapolated_ms"].max()
        how_far = f", by up to {reach / 1000:.1f} s" if pd.notna(reach) else ""
        lines.append(f"telemetry extrapolated for {len(extrapolated)} frames (not bracketed by samples{how_far}): "
                     "dataset.load(run).extrapolated lists them")
    return lines
