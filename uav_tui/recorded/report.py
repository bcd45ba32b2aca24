"""``uav-tui report [RUN]``: a recorded run's plots as PNG files in its folder, plus a short text summary.

Plots are drawn on plain ``matplotlib.figure.Figure`` objects (the Agg renderer, no pyplot, no
display needed): ``track.png`` (ground track, NED east/north coloured by time, executed vectors as
arrows, the geo-located target positions as crosses), ``flight.png`` (altitude, attitude, commanded vs
actual velocity, autonomy shaded), ``processing.png`` (processed FPS and latency over time), ``box.png``
(the tracked box's centre and size over time), ``extra.png`` (each ``tmMgr.save`` field that changes,
over time on its own axis); ``summary.txt``; and ``report.html``, all of it in one self-contained page
(images embedded) to open on the drone or copy off it.
"""

from __future__ import annotations

import base64
import html
import io
import logging
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from uav_tui.config import SafetyConfig
from uav_tui.flight.autonomy import check_vector
from uav_tui.flight.geolocate import EARTH_RADIUS_M, OK
from uav_tui.output.text import safe
from uav_tui.recorded.dataset import Dataset, load
from uav_tui.recorded.report_events import executed_count, landing_lines, problem_lines
from uav_tui.recorded.report_replay import REPLAY_PLOT, replay_figure
from uav_tui.recorded.telemetry_notes import telemetry_notes
from uav_tui.recording.crash import CRASH_FILE, crash_summary
from uav_tui.recording.run_info import replace_file

logger = logging.getLogger(__name__)

PLOTS = ("track.png", "flight.png", "processing.png", "box.png", "extra.png")
"""The plots a report writes into the run folder (and ``summary.txt``, ``report.html``)."""

RATE_WINDOW_S = 1.0
"""The processing rate is counted over this many seconds."""

MIN_TRACK_M = 2.0
"""The ground track's axes span at least this much, so that GPS noise is not drawn as a flight."""

MAX_ARROWS = 40
"""At most this many executed vectors are drawn on the ground track (evenly spread over the run)."""


def write_report(run_dir: str | Path) -> tuple[list[Path], str]:
    """Draw every plot of the run in ``run_dir`` into that folder.

    Returns:
        ``(paths written, summary text)``.

    Raises:
        OSError: a file could not be written (a full disk); each file is written whole or not at all.
    """
    run = load(run_dir)
    paths, images = [], {}
    figures = draw(run)
    replayed = replay_figure(run)  # a replayed run: its vectors beside the recorded run's
    if replayed is not None:
        figures[REPLAY_PLOT] = replayed
    for name, figure in figures.items():
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=100)
        images[name] = buffer.getvalue()
        path = run.path / name
        replace_file(path, images[name])
        paths.append(path)
    text = summary(run)
    replace_file(run.path / "summary.txt", text + "\n")
    replace_file(run.path / "report.html", _html(run.path.name, text, images))
    paths += [run.path / "summary.txt", run.path / "report.html"]
    return paths, text


def draw(run: Dataset) -> dict[str, Figure]:
    """Every plot of ``run``, by its file name in :data:`PLOTS`."""
    figures = {}
    for name, paint in zip(PLOTS, (_track, _flight, _processing, _box, _extra), strict=True):
        figures[name] = Figure(figsize=(8, 6), layout="constrained")
        paint(run, figures[name])
    return figures


def _html(title: str, text: str, images: dict[str, bytes]) -> str:
    """One page with everything inline: no file beside it and nothing from the network is needed."""
    figures = "\n".join(f'<figure><img alt="{html.escape(name)}" src="data:image/png;base64,'
                        f'{base64.b64encode(data).decode()}"><figcaption>{html.escape(name)}</figcaption></figure>'
                        for name, data in images.items())
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>uav-tui run {html.escape(title)}'
            '</title>\n<style>body{font-family:sans-serif;margin:1em auto;max-width:820px}img{max-width:100%}'
            'pre{background:#f4f4f4;padding:.6em;white-space:pre-wrap}</style></head>\n'
            f'<body><h1>uav-tui run {html.escape(title)}</h1>\n<pre>{html.escape(text)}</pre>\n{figures}\n'
            '</body></html>\n')


def summary(run: Dataset) -> str:
    """A few lines: duration, frames, rates, latency, vectors, telemetry, distance, problems (each one :func:`safe`)."""
    frames, telemetry, events = run.frames, run.telemetry, run.events
    duration = _duration_s(run)
    latency = _latency_ms(frames)
    with_vector = int(frames["vx"].notna().sum())
    lines = [
        f"run {run.path.name}: {duration:.1f} s, processor {run.info.get('processor', {}).get('name', '?')}, "
        f"source {run.info.get('source', {}).get('uri', '?')}, "
        f"fc {run.info.get('controller', {}).get('fc', '?')}",
        f"frames: {len(frames)} processed ({len(frames) / duration if duration else 0:.1f}/s), "
        f"{int(frames['saved'].fillna(False).sum())} saved, {int(frames['error'].notna().sum())} with errors",
        f"latency capture->result: p50 {_pct(latency, 50)} ms, p95 {_pct(latency, 95)} ms",
        f"vectors: {with_vector} proposed, {executed_count(frames)} executed (clamped ones too)",
        *landing_lines(frames, telemetry, target_positions(run)),
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
    lines += problem_lines(events)
    drops = run.info.get("recording", {}).get("dropped")
    if drops:
        lines.append(f"recorder dropped {drops} items: {run.info['recording'].get('drops')}")
    if crash := crash_summary(run.path):
        lines.append(f"the process crashed: {crash}; {CRASH_FILE} has every thread's stack; data up to the "
                     "last flush")
    elif run.info.get("end_wall_ns") is None:
        lines.append("the run did not end cleanly (no end time in run.json): data up to the last flush")
    lines += telemetry_notes(run)
    lines += [f"damaged run: {problem}" for problem in run.problems]  # read around, drawn without
    return "\n".join(safe(line) for line in lines)  # names, paths and URIs from the run: escaped, redacted


def _track(run: Dataset, figure: Figure) -> None:
    ax = figure.add_subplot()
    ax.set_title("Ground track (NED, relative to home)")
    ax.set_xlabel("east, m")
    ax.set_ylabel("north, m")
    track = run.telemetry[["t_s", "north_m", "east_m"]].astype("float64")
    track = track[np.isfinite(track).all(axis=1)]
    if track.empty:
        _nothing(ax, "no position telemetry in this run")
        return
    points = ax.scatter(track["east_m"], track["north_m"], c=track["t_s"], cmap="viridis", s=6, zorder=3)
    figure.colorbar(points, ax=ax, label="time, s")
    targets, detected = target_positions(run), target_positions(run, detections=True)
    if len(targets):
        ax.scatter(targets["east_m"], targets["north_m"], marker="x", s=14, color="tab:red", alpha=0.7, zorder=4,
                   label=f"target ({len(targets)} frames geo-located)")
    if len(detected):
        ax.scatter(detected["east_m"], detected["north_m"], marker="+", s=14, color="tab:orange", alpha=0.6, zorder=4,
                   label=f"detections ({len(detected)} geo-located)")
    east = pd.concat([track["east_m"], targets["east_m"], detected["east_m"]])
    north = pd.concat([track["north_m"], targets["north_m"], detected["north_m"]])
    # Square limits, at least MIN_TRACK_M wide: a vehicle that did not move is not drawn on centimetre axes.
    half = max((east.max() - east.min()) * 1.1, (north.max() - north.min()) * 1.1, MIN_TRACK_M) / 2
    ax.set_xlim((east.max() + east.min()) / 2 - half, (east.max() + east.min()) / 2 + half)
    ax.set_ylim((north.max() + north.min()) / 2 - half, (north.max() + north.min()) / 2 + half)
    ax.set_aspect("equal", adjustable="box")
    ax.grid(True, alpha=0.3)
    _executed_arrows(run, ax, 2 * half)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper left", fontsize="small", framealpha=0.6)


def target_positions(run: Dataset, *, detections: bool = False) -> pd.DataFrame:
    """``t_s``, ``north_m``, ``east_m`` of every geo-located target (``target_status`` ok; with ``detections``, of
    every geo-located detection), in the track's local metres: the frame's own position plus the target's offset
    from it (the flat-earth step of :mod:`uav_tui.flight.geolocate` undone), so no home position is needed."""
    columns = ["t_s", "north_m", "east_m", "lat_deg", "lon_deg", "target_lat_deg", "target_lon_deg"]
    frames = run.frames
    if detections:  # each with its frame's position
        frames = run.detections.merge(frames[["frame_id", *columns[1:5]]], on="frame_id")
    rows = frames.loc[(frames["target_status"] == OK).fillna(False), columns].astype("float64")
    rows = rows[np.isfinite(rows).all(axis=1)]
    north = rows["north_m"] + np.radians(rows["target_lat_deg"] - rows["lat_deg"]) * EARTH_RADIUS_M
    east = rows["east_m"] + np.radians(rows["target_lon_deg"] - rows["lon_deg"]) * EARTH_RADIUS_M \
        * np.cos(np.radians(rows["lat_deg"]))
    return pd.DataFrame({"t_s": rows["t_s"], "north_m": north, "east_m": east})


def _executed_arrows(run: Dataset, ax: Axes, span_m: float) -> None:
    """The executed vectors as arrows (direction and speed over ground) on at most :data:`MAX_ARROWS` frames,
    evenly spread: one marker per frame would paint over the track (2,614 in a 90 s flight). The fastest is
    a tenth of the plot long."""
    columns = ["east_m", "north_m", "yaw_deg", "vx", "vy"]
    executed = run.frames.loc[run.frames["decision"].fillna("").str.startswith("executed"), columns]
    executed = executed.astype("float64")
    executed = executed[np.isfinite(executed).all(axis=1)]
    if executed.empty:
        return
    shown = executed.iloc[np.unique(np.linspace(0, len(executed) - 1, min(len(executed), MAX_ARROWS)).astype(int))]
    yaw = np.radians(shown["yaw_deg"])
    north = shown["vx"] * np.cos(yaw) - shown["vy"] * np.sin(yaw)
    east = shown["vx"] * np.sin(yaw) + shown["vy"] * np.cos(yaw)
    fastest = float(np.hypot(north, east).max()) or 1.0
    every = "" if len(shown) == len(executed) else f", {len(shown)} of {len(executed)} shown"
    ax.quiver(shown["east_m"], shown["north_m"], east, north, color="tab:red", alpha=0.6, width=0.003, zorder=4,
              angles="xy", scale_units="xy", scale=fastest / (0.1 * span_m),
              label=f"executed vectors (fastest {fastest:.2g} m/s){every}")


def _flight(run: Dataset, figure: Figure) -> None:
    figure.set_size_inches(8, 8)
    altitude, attitude, velocity = figure.subplots(3, 1, sharex=True)
    telemetry = run.telemetry
    altitude.set_title("Altitude, attitude and velocity (autonomy on: shaded)")
    altitude.set_ylabel("relative altitude, m")
    attitude.set_ylabel("degrees")
    velocity.set_xlabel("time since start, s")
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
    _velocity(run, velocity)
    for start, end in autonomy_spans(run):
        for ax in (altitude, attitude, velocity):
            ax.axvspan(start, end, color="tab:green", alpha=0.12, linewidth=0)
    for ax in (altitude, attitude, velocity):
        ax.grid(True, alpha=0.3)


def _velocity(run: Dataset, ax: Axes) -> None:
    """Body-frame velocity (forward, right): commanded vectors as segments over their duration, actual as lines."""
    ax.set_ylabel("body velocity, m/s")
    telemetry = run.telemetry[["t_s", "vn_ms", "ve_ms", "yaw_deg"]].dropna()
    commanded = commanded_vectors(run)
    if telemetry.empty and commanded.empty:
        _nothing(ax, "no velocity telemetry and no vectors")
        return
    yaw = np.radians(telemetry["yaw_deg"].astype("float64"))
    north, east = telemetry["vn_ms"].astype("float64"), telemetry["ve_ms"].astype("float64")
    actual = {"forward": north * np.cos(yaw) + east * np.sin(yaw), "right": -north * np.sin(yaw) + east * np.cos(yaw)}
    for (axis, values), colour in zip(actual.items(), ("tab:blue", "tab:orange"), strict=True):
        ax.plot(telemetry["t_s"], values, color=colour, linewidth=1, label=f"{axis} actual")
        if len(commanded):
            ax.hlines(commanded[axis], commanded["start_s"], commanded["end_s"], colors=colour, linewidths=2.5,
                      alpha=0.6, label=f"{axis} commanded")
    ax.legend(loc="best", fontsize="small", ncols=2)


def commanded_vectors(run: Dataset) -> pd.DataFrame:
    """Every vector flown, the processor's (executed) and the operator's (``vector`` command), clamped to the
    run's safety limits: start_s, end_s, forward, right; a vector ends after its duration or when the next one
    replaces it."""
    frames = run.frames[run.frames["decision"].fillna("").str.startswith("executed")]
    proposed: list[tuple[float, tuple[float, ...]]] = [
        (t, (vx, vy, vt)) for t, vx, vy, vt in frames[["t_s", "vx", "vy", "vt"]].itertuples(index=False)]
    operator = run.events[(run.events["kind"] == "command").fillna(False)
                          & run.events["message"].str.match(r"vector \S+ \S+ \S+$", na=False)]
    for t, message in operator[["t_s", "message"]].itertuples(index=False):
        proposed.append((t, tuple(float(word) for word in message.split()[1:])))
    try:
        safety = SafetyConfig(**run.info.get("config", {}).get("safety", {}))
    except TypeError:  # recorded by a version with other keys: the defaults
        safety = SafetyConfig()
    flown = [(t, check_vector(vector, safety)[0]) for t, vector in proposed]  # clamped as they were flown
    rows = [(t, *vector) for t, vector in flown if vector is not None]
    table = pd.DataFrame(rows, columns=["start_s", "forward", "right", "t"], dtype="float64").sort_values("start_s")
    replaced = table["start_s"].shift(-1).fillna(np.inf)
    table["end_s"] = np.minimum(table["start_s"] + table["t"], replaced)
    return table.reset_index(drop=True)


def autonomy_spans(run: Dataset) -> list[tuple[float, float]]:
    """(start, end) seconds of every stretch with autonomy on (a run that ended with it on: to the end)."""
    spans, since = [], None
    switches = run.events[(run.events["kind"] == "autonomy").fillna(False)].dropna(subset=["message"])
    for t, message in switches[["t_s", "message"]].itertuples(index=False):
        if message == "autonomy ON" and since is None:
            since = t
        elif message.startswith("autonomy OFF") and since is not None:
            spans.append((since, t))
            since = None
    if since is not None:
        spans.append((since, _duration_s(run)))
    return spans


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
    done_s = (frames["t_end_ns"].astype("float64") - frames["t_end_ns"].min()) / 1e9
    rate.plot(*processing_rate(frames["t_s"], done_s), color="tab:blue")
    rate.set_ylim(bottom=0)
    latency.plot(frames["t_s"], _latency_ms(frames), ".", markersize=2, label="capture -> result")
    busy = (frames["t_end_ns"] - frames["t_start_ns"]).astype("float64") / 1e6
    latency.plot(frames["t_s"], busy, ".", markersize=2, label="processing")
    latency.legend(loc="best")
    for ax in (rate, latency):
        ax.grid(True, alpha=0.3)


def processing_rate(t_s: pd.Series, done_s: pd.Series) -> tuple[np.ndarray, np.ndarray]:
    """Frames finished per second over the last :data:`RATE_WINDOW_S` before each frame (from one full window
    after the first frame on: a shorter window at the start would turn the first few frames into a spike)."""
    done = done_s.to_numpy(dtype="float64")
    in_window = np.arange(1, len(done) + 1) - np.searchsorted(done, done - RATE_WINDOW_S, side="right")
    full = done >= RATE_WINDOW_S
    return t_s.to_numpy(dtype="float64")[full], in_window[full] / RATE_WINDOW_S


def _box(run: Dataset, figure: Figure) -> None:
    """The processor's tracked ``box`` over time: its centre and its size, in frame pixels (gaps: nothing tracked)."""
    centre, size = figure.subplots(2, 1, sharex=True)
    centre.set_title("Tracked box (frame pixels; gaps: nothing tracked)")
    centre.set_ylabel("centre, px")
    size.set_ylabel("size, px")
    size.set_xlabel("time since start, s")
    frames = run.frames[["t_s", "box_x", "box_y", "box_w", "box_h"]].astype("float64")
    if frames[["box_x", "box_y", "box_w", "box_h"]].isna().all().all():
        _nothing(centre, "the processor reported no box")
        return
    t_s = frames["t_s"]
    middle = {"x": frames["box_x"] + frames["box_w"] / 2, "y": frames["box_y"] + frames["box_h"] / 2}
    for ax, values in ((centre, middle), (size, {"width": frames["box_w"], "height": frames["box_h"]})):
        for label, series in values.items():
            ax.plot(t_s, series, linewidth=1, label=label)  # NaN rows break the line where tracking was lost
        ax.legend(loc="best", fontsize="small")
        ax.grid(True, alpha=0.3)


def _extra(run: Dataset, figure: Figure) -> None:
    """Each numeric ``tmMgr.save`` field that changes, over time on its own axis; the others named in one line."""
    varying, steady = [], []
    for name in run.extra_columns:
        column = run.frames[name]
        if not pd.api.types.is_numeric_dtype(column) or pd.api.types.is_bool_dtype(column):
            continue
        values = column.astype("float64").to_numpy()
        values = values[np.isfinite(values)]
        with np.errstate(over="ignore"):
            span = float(np.ptp(values)) if len(values) else 0.0
        if len(values) > 1 and 0 < span < np.inf:
            varying.append(name)
        else:
            steady.append(f"{name} = {values[0]:.6g}" if len(values) and span == 0 and len(values) > 1 else
                          f"{name} ({len(values)} finite value{'s' * (len(values) != 1)})")
    note = f"not drawn (constant or too few values): {', '.join(steady)}" if steady else ""
    if not varying:
        ax = figure.add_subplot()
        ax.set_title("Processor fields saved with tmMgr.save")
        _nothing(ax, "the processor saved no numeric field that changes" + (f"\n{note}" if note else ""))
        return
    figure.set_size_inches(8, max(3.0, 1.6 * len(varying) + 0.8))
    axes = figure.subplots(len(varying), 1, sharex=True, squeeze=False)[:, 0]
    axes[0].set_title("Processor fields saved with tmMgr.save (each on its own scale)")
    axes[-1].set_xlabel("time since start, s" + (f"\n{note}" if note else ""))
    for ax, name in zip(axes, varying, strict=True):
        rows = run.frames[["t_s", name]].astype("float64")
        rows = rows[np.isfinite(rows).all(axis=1)]
        ax.plot(rows["t_s"], rows[name], ".-", markersize=3, linewidth=0.8)
        ax.set_ylabel(name, fontsize="small")
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
