"""The algorithm panel: which processor runs and where, what it can do, its last vector and errors."""

from __future__ import annotations

from rich.text import Text

from uav_tui.status import CoreStatus
from uav_tui.tui._panel import StatusPanel

CAPABILITY_LABELS = {"catch_cmd": "ROI", "customize_processing": "F1-F4", "getPreparedVector": "vector"}
"""Optional processor methods, as the operator knows them."""


class AlgorithmPanel(StatusPanel):
    """The researcher's processor: name, optional methods, last vector and decision, errors."""

    TITLE = "Algorithm"

    def describe(self, status: CoreStatus) -> Text:
        has = " ".join(label for method, label in CAPABILITY_LABELS.items() if method in status.capabilities)
        auto = Text(f"{status.vectors_executed} flown, {status.vectors_rejected} rejected")
        if status.autonomy_stop_reason and not status.autonomy:
            auto.append(" ").append(self.styled(f"stopped: {status.autonomy_stop_reason}", "bad"))
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
        return self.rows(("proc", name), ("has", has or "photo_processing only"), ("vec", vector), ("auto", auto),
                         ("err", errors))
