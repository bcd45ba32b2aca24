"""The link's quality where the autopilot (or a telemetry radio) reports it, as ``link_quality_pct`` updates.

Two sources, read as raw messages (MavlinkDirect):

- RC_CHANNELS ``rssi`` from the autopilot: the RC receiver's signal, 0-254 (255: unknown; ``chancount`` 0: no
  receiver). MAVSDK's ``rc_status`` is not used: its ``signal_strength_percent`` is that 0-254 value unscaled, and
  it keeps the last value once the autopilot sends 255 (MAVSDK v2 ``telemetry_impl.cpp: process_rc_channels``).
- RADIO_STATUS ``rssi`` / ``remrssi`` from any system (a SiK radio sends it as its own system, 51): both ends of
  a telemetry radio's link, 0-254, 255 unknown. The scale is the device's (a SiK radio's is not a percentage).

Each is scaled to 0-100 %; the update is the weakest that was reported within :data:`FRESH_S`, None when none
was (unknown: the envelope's floor never acts on it).
"""

from __future__ import annotations

import contextlib
import json
import time
from collections.abc import AsyncGenerator, Callable
from typing import Any

from mavsdk.asyncio.plugins.mavlink_direct import MavlinkDirectAsync, MavlinkMessage

Update = dict[str, Any]

FRESH_S = 3.0
"""A source that reported nothing for this long no longer counts (RC_CHANNELS and RADIO_STATUS come at 1-5 Hz)."""

UNKNOWN = 255
"""MAVLink's "invalid/unknown" rssi."""


def _percent(*values: Any) -> float | None:
    """The weakest of ``values`` (0-254) in percent; None when none is known."""
    known = [int(v) for v in values if isinstance(v, int | float) and 0 <= v < UNKNOWN]
    return min(known) * 100 / 254 if known else None


def from_rc_channels(fields: dict[str, Any]) -> float | None:
    """RC_CHANNELS' receiver signal in percent, None without a receiver or a known rssi."""
    return _percent(fields.get("rssi")) if fields.get("chancount") else None


def from_radio_status(fields: dict[str, Any]) -> float | None:
    """RADIO_STATUS' weaker end of the radio link in percent, None when neither is known."""
    return _percent(fields.get("rssi"), fields.get("remrssi"))


class LinkQuality:
    """The weakest fresh report of every source, as one ``link_quality_pct`` update per report."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self.clock = clock
        self._reports: dict[str, tuple[float | None, float]] = {}

    def report(self, source: str, percent: float | None) -> Update:
        now = self.clock()
        self._reports[source] = (percent, now)
        fresh = [p for p, at in self._reports.values() if p is not None and now - at <= FRESH_S]
        return {"link_quality_pct": min(fresh) if fresh else None}


def link_readers(direct: MavlinkDirectAsync, system_id: int) -> dict[str, AsyncGenerator[Update, None]]:
    """The two readers (task name -> updates), sharing one :class:`LinkQuality`."""
    quality = LinkQuality()
    return {"telemetry-rc-channels": _reports(direct, "RC_CHANNELS", from_rc_channels, quality, system_id),
            "telemetry-radio-status": _reports(direct, "RADIO_STATUS", from_radio_status, quality, None)}


async def _reports(direct: MavlinkDirectAsync, name: str, convert: Callable[[dict[str, Any]], float | None],
                   quality: LinkQuality, system_id: int | None) -> AsyncGenerator[Update, None]:
    """An update for each ``name`` message (from ``system_id`` only, unless None), as they arrive."""
    async with contextlib.aclosing(direct.subscribe_message(name)) as messages:  # unsubscribed when closed
        async for message in messages:
            if (system_id is None or message.system_id == system_id) and (fields := _fields(message)) is not None:
                yield quality.report(name, convert(fields))


def _fields(message: MavlinkMessage) -> dict[str, Any] | None:
    try:
        fields = json.loads(message.fields_json)
    except (TypeError, ValueError):
        return None
    return fields if isinstance(fields, dict) else None
