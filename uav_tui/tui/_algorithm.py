"""The algorithm panel: which processor runs and where, what it tracks, its last vector and errors."""

from __future__ import annotations

from rich.text import Text

from uav_tui.flight.autonomy import Verdict
from uav_tui.flight.geo_detections import describe_shown
from uav_tui.flight.geolocate import describe as describe_target
from uav_tui.hosting.host import HostState
from uav_tui.status import CoreStatus
from uav_tui.tui._panel import StatusPanel

MIN_NAME = 6
"""Characters of the processor's name kept when its host's state needs the room (an 80-column terminal)."""


class AlgorithmPanel(StatusPanel):
    """The researcher's processor: name and host, its ``box``, last vector and decision, autonomy, the landing
    targets or the gimbal, errors.

    The optional methods it lacks show as dimmed keys (ROI, F1-F4) and in the vector row. Where the row is
    too narrow for the processor's name and its host's state (pid, memory), the name is shortened.
    """

    TITLE = "Algorithm"

    def describe(self, status: CoreStatus) -> Text:
        box = "none" if status.box is None else "{},{} {}x{}".format(*status.box)
        if status.target is not None and (where := describe_target(status.target)):
            box += f" @ {where}"
        if detected := describe_shown(status.detections, status.detections_total, status.tracks_total):
            box += f"; {detected}"  # one row, cut at the panel's edge
        if status.lock:
            box = f"lock {status.lock}; {box}"
        auto = Text(f"{status.vectors_executed} flown, {status.vectors_rejected} rejected")
        if status.autonomy_stop_reason and not status.autonomy:
            auto.append(" ").append(self.styled(f"stopped: {status.autonomy_stop_reason}", "bad"))
        if "getPreparedVector" not in status.capabilities:
            vector = Text("no getPreparedVector")
        else:
            vector = Text("none" if status.last_vector is None else
                          "({:+.2f}, {:+.2f}, {:.1f}s)".format(*status.last_vector))
        if status.last_decision:
            level = "good" if status.last_verdict is Verdict.EXECUTED else "warn"
            vector.append(" ").append(self.styled(status.last_decision, level))
        errors = Text(str(status.pipeline.errors))
        if status.processor_error:
            errors.append(" ").append(self.styled(status.processor_error, "bad"))
        out_label, out = self._outputs(status)
        labels = ("proc", "box", "vec", "auto", out_label, "err")
        proc = Text(status.processor.rsplit(":", 1)[-1])
        if (host := status.processor_state) is not None:  # where it runs: its own process (pid, memory) or a thread
            running = host.phase.state is HostState.RUNNING
            summary = Text(" ").append_text(self.styled(host.summary(), "good" if running else "bad"))
            room = self.room_before(summary, labels, MIN_NAME)
            if room is not None and len(proc) > room:  # the name yields: it never changes
                proc.truncate(room, overflow="ellipsis")
            proc.append_text(summary)
        values: tuple[Text | str, ...] = (proc, box, vector, auto, out, errors)
        return self.rows(*zip(labels, values, strict=True))

    def _outputs(self, status: CoreStatus) -> tuple[str, Text]:
        """The row of the outputs besides the vector: ``land`` (precland and its landing targets sent), ``gim`` (the
        gimbal's attitude and the pointing sent), ``out`` with both."""
        land = Text()
        if "getLandingTarget" in status.capabilities:
            land.append_text(self.styled("ON", "good") if status.precland else Text("off"))
            land.append(f", {status.landing_targets_sent} sent")
            if status.landing_targets_failed:
                land.append(" ").append(self.styled(f"{status.landing_targets_failed} failed", "bad"))
            if status.landing_none_reason:
                land.append(", ").append(self.styled(status.landing_none_reason, "warn"))
        gimbal = status.gimbal_summary().removeprefix("gimbal ")
        if land and gimbal:
            return "out", Text("land ").append_text(land).append(f"; gim {gimbal}")
        return ("land", land) if land else ("gim", Text(gimbal or "none"))
