"""The MAVLink mission protocol, enough for plans to be uploaded and downloaded: missions, geofences, rally points.

Each ``mission_type`` keeps its own list of items (MISSION_ITEM_INT). Upload: MISSION_COUNT, then the simulator
asks for each item (MISSION_REQUEST_INT) and ends with MISSION_ACK; download: MISSION_REQUEST_LIST answered with
MISSION_COUNT, then each MISSION_REQUEST_INT (or MISSION_REQUEST) with its item. MISSION_CLEAR_ALL empties a
list. The items are stored, not flown: what reads them is the platform's fence check (PX4 geofence plans).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from pymavlink.dialects.v20 import common as mavlink

M = mavlink



@dataclass(slots=True)
class _Upload:
    mission_type: int
    count: int
    items: list[Any] = field(default_factory=list)


class MissionStore:
    """The plans the simulated vehicle holds, by ``mission_type``; :meth:`on_message` answers the protocol."""

    KINDS = frozenset({"MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_REQUEST_LIST", "MISSION_REQUEST_INT",
                       "MISSION_REQUEST", "MISSION_CLEAR_ALL", "MISSION_ACK"})
    """The messages :meth:`on_message` takes."""

    def __init__(self, encoder: mavlink.MAVLink) -> None:
        self.enc = encoder
        self.plans: dict[int, list[Any]] = {}
        """mission_type -> its items (MISSION_ITEM_INT messages as received)."""
        self._upload: _Upload | None = None

    def on_message(self, msg: Any) -> list[mavlink.MAVLink_message]:
        """The answers to one mission-protocol message (none to a MISSION_ACK, the end of a download)."""
        kind, peer = msg.get_type(), (msg.get_srcSystem(), msg.get_srcComponent())
        kind_of = getattr(msg, "mission_type", M.MAV_MISSION_TYPE_MISSION)
        if kind == "MISSION_COUNT":
            self._upload = _Upload(kind_of, msg.count)
            return [self._next(peer)]
        if kind == "MISSION_ITEM_INT" and self._upload is not None and self._upload.mission_type == kind_of:
            if msg.seq == len(self._upload.items):
                self._upload.items.append(msg)
            return [self._next(peer)]
        if kind == "MISSION_REQUEST_LIST":
            return [self.enc.mission_count_encode(*peer, len(self.plans.get(kind_of, [])), kind_of)]
        if kind in ("MISSION_REQUEST_INT", "MISSION_REQUEST"):
            items = self.plans.get(kind_of, [])
            if not 0 <= msg.seq < len(items):
                return [self.enc.mission_ack_encode(*peer, M.MAV_MISSION_INVALID_SEQUENCE, kind_of)]
            return [self._item(peer, items[msg.seq], kind_of)]
        if kind == "MISSION_CLEAR_ALL":
            types = list(self.plans) if kind_of == M.MAV_MISSION_TYPE_ALL else [kind_of]
            for mission_type in types:
                self.plans.pop(mission_type, None)
            return [self.enc.mission_ack_encode(*peer, M.MAV_MISSION_ACCEPTED, kind_of)]
        return []

    def _next(self, peer: tuple[int, int]) -> mavlink.MAVLink_message:
        """Ask for the next item of the upload, or end it (stored) with MISSION_ACK."""
        upload = self._upload
        assert upload is not None
        if len(upload.items) < upload.count:
            return self.enc.mission_request_int_encode(*peer, len(upload.items), upload.mission_type)
        self.plans[upload.mission_type], self._upload = upload.items, None
        return self.enc.mission_ack_encode(*peer, M.MAV_MISSION_ACCEPTED, upload.mission_type)

    def _item(self, peer: tuple[int, int], item: Any, mission_type: int) -> mavlink.MAVLink_message:
        return self.enc.mission_item_int_encode(
            *peer, item.seq, item.frame, item.command, item.current, item.autocontinue, item.param1, item.param2,
            item.param3, item.param4, item.x, item.y, item.z, mission_type)
