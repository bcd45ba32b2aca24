"""``replay.png`` in a replayed run's report: the recorded processor's vectors beside the replayed one's.

Drawn by ``uav-tui report`` when the run's ``run.json`` names the run it replays (``replay_of``) and
that run is still there: vx and vy per frame from both, the frames whose vector the autonomy gate
executed (or would have), and the tracked ``box`` (``box_x`` .. ``box_h``) when both runs report one.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from matplotlib.figure import Figure

from uav_tui.recorded.dataset import Dataset, compare, load

REPLAY_PLOT = "replay.png"
BOX = ("box_x", "box_y", "box_w", "box_h")


def replay_figure(run: Dataset) -> Figure | None:
    """The ``replay.png`` figure of a replayed run; None when ``run`` is not a replay (or its source is gone)."""
    source = Path(run.info.get("replay_of", {}).get("run", ""))
    if not source.parts or not (source / "run.json").is_file():
        return None
    original = load(source)
    figure = Figure(figsize=(8, 8), layout="constrained")
    paint_replay(compare(original, run), figure, names=(_processor_name(original), _processor_name(run)))
    return figure


def paint_replay(joined: pd.DataFrame, figure: Figure, names: tuple[str, str]) -> None:
    """Plot a :func:`uav_tui.recorded.dataset.compare` table: the flight (``_a``) and its replay (``_b``)."""
    sides = (("a", f"flight ({names[0]})", "-", "x"), ("b", f"replay ({names[1]})", "--", "+"))
    boxed = [side for side in sides if all(f"{c}_{side[0]}" in joined and joined[f"{c}_{side[0]}"].notna().any()
                                           for c in BOX)]  # a run whose processor tracked no box has no panel
    axes = figure.subplots(3 if boxed else 2, 1, sharex=True)
    t_s = joined["t_s_a"]
    figure.suptitle(f"Flight vs replay: the vector of the {len(joined)} frames both processed")
    for ax, component in zip(axes, ("vx", "vy"), strict=False):
        for side, label, style, marker in sides:
            proposed = joined[f"{component}_{side}"].notna()  # vectors are sparse: join the frames that had one
            ax.plot(t_s[proposed], joined.loc[proposed, f"{component}_{side}"], style, linewidth=1, label=label)
            executed = joined[f"decision_{side}"].fillna("").str.startswith("executed")
            ax.plot(t_s[executed], joined.loc[executed, f"{component}_{side}"], marker, markersize=5,
                    label=f"{label.split(' ')[0]}: executed")
        ax.set_ylabel(f"{component}, m/s")
        ax.legend(loc="best", fontsize="small")
        ax.grid(True, alpha=0.3)
    if boxed:
        ax = axes[2]
        for side, label, style, _ in boxed:
            ax.plot(t_s, joined[f"box_x_{side}"] + joined[f"box_w_{side}"] / 2, style, label=f"{label}: box centre x")
            ax.plot(t_s, joined[f"box_y_{side}"] + joined[f"box_h_{side}"] / 2, style, label=f"{label}: box centre y")
        ax.set_ylabel("box centre, px")
        ax.legend(loc="best", fontsize="small")
        ax.grid(True, alpha=0.3)
    axes[-1].set_xlabel("time since the flight started, s")


def _processor_name(run: Dataset) -> str:
    """The processor as the user named it (``position_hold``, ``mine.py:Mine``)."""
    processor = run.info.get("processor", {})
    return str(processor.get("spec") or processor.get("name") or "?")
