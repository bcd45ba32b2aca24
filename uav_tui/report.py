"""``uav-tui report RUN``: a recorded run's plots as PNG files in its folder, plus a short text summary.

Plots are drawn on plain ``matplotlib.figure.Figure`` objects (the Agg renderer, no pyplot, no
display needed): ``track.png`` (ground track, NED east/north coloured by time, executed vectors
marked), ``flight.png`` (altitude and attitude over time), ``processing.png`` (processed FPS and
latency over time), ``extra.png`` (the processor's ``tmMgr.save`` fields over time); ``summary.txt``.
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from uav_tui.dataset import Dataset, load
from uav_tui.report_replay import write_replay_plot

logger = logging.getLogger(__name__)

PLOTS = ("track.png", "flight.png", "processing.png", "extra.png")
"""The files a report writes into the run folder (and ``summary.txt``)."""


def write_report(run_dir: str | Path) -> tuple[list[Path], str]:
    """Draw every plot of the run in ``run_dir`` into that folder.

    Returns:
        ``(paths written, summary text)``.
    """
    run = load(run_dir)
    painters = (_track, _flight, _processing, _extra)
    paths = []
    for name, paint in zip(PLOTS, painters, strict=True):
        figure = Figure(figsize=(8, 6), layout="constrained")
        paint(run, figure)
        path = run.path / name
        figure.savefig(path, dpi=100)
        paths.append(path)
    replay_plot = write_replay_plot(run)  # a replayed run: its vectors beside the recorded run's
    if replay_plot is not None:
        paths.append(replay_plot)
    text = summary(run)
    (run.path / "summary.txt").write_text(text + "\n")
    paths.append(run.path / "summary.txt")
    return paths, text


def summary(run: Dataset) -> str:
    """A few lines: duration, frames, rates, latency, vectors, telemetry, distance, problems."""
    frames, telemetry, events = run.frames, run.telemetry, run.events
    duration = _duration_s(run)
    latency = _latency_ms(frames)
    decisions = frames["decision"].fillna("")
    executed = int((decisions == "executed").sum())
    with_vector = int(frames["vx"].notna().sum())
    lines = [
        f"run {run.path.name}: {duration:.1f} s, processor {run.info.get('processor', {}).get('name', '?')}, "
        f"source {run.info.get('source', {}).get('uri', '?')}, fc {run.info.get('controller', {}).get('fc', '?')}",
        f"frames: {len(frames)} processed ({len(frames) / duration if duration else 0:.1f}/s), "
        f"{int(frames['saved'].fillna(False).sum())} saved, {int(frames['error'].notna().sum())} with errors",
        f"latency capture->result: p50 {_pct(latency, 50)} ms, p95 {_pct(latency, 95)} ms",
        f"vectors: {with_vector} proposed, {executed} executed",
    ]
    if len(telemetry):
        track = telemetry[["north_m", "east_m"]].dropna().to_numpy()
        distance = float(np.sum(np.hypot(*np.diff(track, axis=0).T))) if len(track) > 1 else 0.0
        altitude = telemetry["rel_alt_m"].max()
        lines.append(f"telemetry: {len(telemetry)} samples, flown {distance:.1f} m, max altitude "
                     f"{altitude:.1f} m" if pd.notna(altitude) else f"telemetry: {len(telemetry)} samples")
    else:
        lines.append("telemetry: none (no flight controller)")
    levels = events["level"].value_counts()
    lines.append(f"events: {len(events)} ({int(levels.get('warning', 0))} warnings, "
                 f"{int(levels.get('error', 0))} errors)")
    drops = run.info.get("recording", {}).get("dropped")
    if drops:
        lines.append(f"recorder dropped {drops} items: {run.info['recording'].get('drops')}")
    if run.info.get("end_wall_ns") is None:
        lines.append("the run did not end cleanly (no end time in run.json): data up to the last flush")
    return "\n".join(lines)


def _track(run: Dataset, figure: Figure) -> None:
    ax = figure.add_subplot()
    ax.set_title("Ground track (NED, relative to home)")
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    track = run.telemetry[["t_s", "north_m", "east_m"]].dropna()
    if track.empty:
        _nothing(ax, "no position telemetry in this run")
        return
    points = ax.scatter(track["east_m"], track["north_m"], c=track["t_s"], cmap="viridis", s=6)
    figure.colorbar(points, ax=ax, label="time, s")
    executed = run.frames[run.frames["decision"] == "executed"].dropna(subset=["north_m", "east_m"])
    if len(executed):
        ax.scatter(executed["east_m"], executed["north_m"], marker="x", color="red", s=40, label="vector executed")
        ax.legend(loc="best")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)


def _flight(run: Dataset, figure: Figure) -> None:
    altitude, attitude = figure.subplots(2, 1, sharex=True)
    telemetry = run.telemetry
    altitude.set_title("Altitude and attitude")
    altitude.set_ylabel("relative altitude, m")
    attitude.set_ylabel("degrees")
    attitude.set_xlabel("time since start, s")
    if telemetry["rel_alt_m"].notna().any():
        altitude.plot(telemetry["t_s"], telemetry["rel_alt_m"], color="tab:blue")
    else:
        _nothing(altitude, "no altitude telemetry")
    drawn = False
    for name in ("roll_deg", "pitch_deg", "yaw_deg"):
        if telemetry[name].notna().any():
            attitude.plot(telemetry["t_s"], telemetry[name], label=name.removesuffix("_deg"), linewidth=1)
            drawn = True
    if drawn:
        attitude.legend(loc="best")
    else:
        _nothing(attitude, "no attitude telemetry")
    for ax in (altitude, attitude):
        ax.grid(True, alpha=0.3)


def _processing(run: Dataset, figure: Figure) -> None:
    rate, latency = figure.subplots(2, 1, sharex=True)
    frames = run.frames
    rate.set_title("Processing")
    rate.set_ylabel("processed frames/s")
    latency.set_ylabel("ms")
    latency.set_xlabel("time since start, s")
    if frames.empty:
        _nothing(rate, "no frames processed")
        return
    done_s = frames["t_end_ns"].astype("float64") / 1e9
    interval = done_s.diff().rolling(10, min_periods=1).mean()  # over the last 10 frames
    rate.plot(frames["t_s"], 1 / interval.where(interval > 0), color="tab:blue")
    rate.set_ylim(bottom=0)
    latency.plot(frames["t_s"], _latency_ms(frames), ".", markersize=2, label="capture -> result")
    busy = (frames["t_end_ns"] - frames["t_start_ns"]).astype("float64") / 1e6
    latency.plot(frames["t_s"], busy, ".", markersize=2, label="processing")
    latency.legend(loc="best")
    for ax in (rate, latency):
        ax.grid(True, alpha=0.3)


def _extra(run: Dataset, figure: Figure) -> None:
    ax = figure.add_subplot()
    ax.set_title("Processor fields saved with tmMgr.save")
    ax.set_xlabel("time since start, s")
    numeric = [name for name in run.extra_columns if pd.api.types.is_numeric_dtype(run.frames[name])
               and not pd.api.types.is_bool_dtype(run.frames[name])]
    if not numeric:
        _nothing(ax, "the processor saved no numeric fields")
        return
    for name in numeric:
        rows = run.frames[["t_s", name]].dropna()
        ax.plot(rows["t_s"], rows[name], ".-", markersize=3, linewidth=0.8, label=name)
    ax.legend(loc="best")
    ax.grid(True, alpha=0.3)


def _latency_ms(frames: pd.DataFrame) -> pd.Series:
    ready = frames["t_vector_ns"].fillna(frames["t_end_ns"])
    return (ready - frames["t_mono_ns"]).astype("float64") / 1e6


def _pct(values: pd.Series, q: float) -> str:
    values = values.dropna()
    return f"{np.percentile(values, q):.1f}" if len(values) else "-"


def _duration_s(run: Dataset) -> float:
    start, end = run.info.get("start_wall_ns"), run.info.get("end_wall_ns")
    if start and end:
        return (end - start) / 1e9
    stamps = [df["t_s"].max() for df in (run.telemetry, run.frames, run.events) if len(df)]
    return float(max(stamps)) if stamps else 0.0


def _nothing(ax: Axes, text: str) -> None:
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, color="gray")
