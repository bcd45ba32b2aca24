"""A vector's end (zero, then the holding mode) belongs to the vector: it is active until the hold is out.

The autopilot side is a stand-in whose hold takes as long as a loaded link's answer can (0.3 s), so the end is
seen however fast the machine is.
"""

from __future__ import annotations

import asyncio

from controllers.mavsdk.vector_stream import VectorStream
from controllers.vector_end import VectorEnd, VectorEndKind

SLOW_HOLD_S = 0.3


class SlowHoldPort:
    """An OffboardPort whose hold is answered ``SLOW_HOLD_S`` late; it records what it was sent."""

    def __init__(self) -> None:
        self.sent: list[tuple[float, float]] = []
        self.holds_done = 0

    async def send_velocity_body(self, forward_ms: float, right_ms: float) -> None:
        self.sent.append((forward_ms, right_ms))

    async def start_offboard(self, *, yield_to_others: bool = False) -> None:
        pass

    async def stop_offboard(self) -> None:
        await asyncio.sleep(SLOW_HOLD_S)
        self.holds_done += 1

    def flight_mode_since(self, t_mono: float) -> str | None:
        return None


async def test_a_completed_vector_is_active_until_its_hold_is_answered() -> None:
    port = SlowHoldPort()
    stream = VectorStream(port)
    await stream.start(0.5, 0.0, 0.2)
    async with asyncio.timeout(5):
        while stream.active:
            await asyncio.sleep(0.01)
    assert port.holds_done == 1  # inactive with the hold still on its way: a caller's next step raced it
    assert port.sent[-1] == (0.0, 0.0)
    assert (stream.last_end, stream.engaged) == (VectorEnd(VectorEndKind.COMPLETED), False)


def test_a_vector_end_reads_as_its_text_always_did() -> None:
    ends = [VectorEnd(), VectorEnd(VectorEndKind.COMPLETED), VectorEnd(VectorEndKind.STOPPED),
            VectorEnd(VectorEndKind.FAILED, "offboard refused"), VectorEnd(VectorEndKind.LEFT_OFFBOARD, "HOLD")]
    assert [str(end) for end in ends] == ["", "completed", "stopped", "failed: offboard refused",
                                          "vehicle left offboard (HOLD)"]
