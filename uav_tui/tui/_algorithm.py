"""The algorithm panel: which processor runs and where, what it tracks, its last vector and errors."""

from __future__ import annotations

from rich.text import Text

from uav_tui.status import CoreStatus
from uav_tui.tui._panel import StatusPanel


class AlgorithmPanel(StatusPanel):
    """The researcher's processor: name and host, its ``box``, last vector and decision, errors.

    The optional methods it lacks show as dimmed keys (ROI, F1-F4) and in the vector row.
    """

    TITLE = "Algorithm"

    def describe(self, status: CoreStatus) -> Text:
        box = "none" if status.box is None else "{},{} {}x{}".format(*status.box)
        auto = Text(f"{status.vectors_executed} flown, {status.vectors_rejected} rejected")
        if status.autonomy_stop_reason and not status.autonomy:
            auto.append(" ").append(self.styled(f"stopped: {status.autonomy_stop_reason}", "bad"))
        if "getPreparedVector" not in status.capabilities:
            vector = Text("no getPreparedVector")
        else:
            vector = Text("none" if status.last_vector is None else
                          "({:+.2f}, {:+.2f}, {:.1f}s)".format(*status.last_vector))
        if status.last_decision:
            level = "good" if status.last_decision.startswith("executed") else "warn"
            vector.append(" ").append(self.styled(status.last_decision, level))
        errors = Text(str(status.pipeline.errors))
        if status.processor_error:
            errors.append(" ").append(self.styled(status.processor_error, "bad"))
        name, host = Text(status.processor.rsplit(":", 1)[-1]), status.processor_state
        if host is not None:  # where it runs: its own process (pid, memory) or a platform thread
            name.append(" ").append(self.styled(host.summary(), "good" if host.state == "running" else "bad"))
        return self.rows(("proc", name), ("box", box), ("vec", vector), ("auto", auto), ("err", errors))
