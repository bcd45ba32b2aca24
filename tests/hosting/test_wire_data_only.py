"""What crosses from the processor's process is data: nothing a processor returns or writes runs code in the platform.

Pickle, the wire before, called whatever ``__reduce__`` a returned object named when the platform read it: a
``getLandingTarget`` returning such an object made the platform itself exit with the processor's chosen status.
"""

from __future__ import annotations

from pathlib import Path

from sources.buffer import FrameBuffer
from tests.hosting.hosts import one_at_a_time, running_worker
from uav_tui.hosting.host import HostPhase, HostState, ProcessedFrame

HOSTILE = '''
import os, struct, sys

from processors import LandingTarget


class Exits:
    """Pickled, it is ``os._exit(77)`` in whichever process reads it."""

    def __reduce__(self):
        return (os._exit, (77,))


class ExitingTarget(LandingTarget):
    __slots__ = ()

    def __reduce__(self):
        return (os._exit, (77,))


class Hostile:
    """Frame 1: a vector that exits when unpickled; 2: a landing target that does; 3: a target made impossible after
    it was built; 4: bytes of its own on the pipe (a frame that is no message) and a plain frame; 5 on: plain."""

    def __init__(self):
        self.tmMgr = None
        self.n = 0

    def photo_processing(self, frame):
        self.n += 1
        if self.n == 4:
            junk = b"\\x93\\x06not a message"
            os.write(int(sys.argv[1]), struct.pack("!i", 4 + len(junk)) + struct.pack("!I", 0) + junk)

    def getPreparedVector(self):
        return Exits() if self.n == 1 else (0.1, 0.0, 0.5)

    def getLandingTarget(self):
        if self.n == 2:
            return ExitingTarget((0.0, 0.0, 1.0), 5.0)
        if self.n == 3:
            target = LandingTarget((0.0, 0.0, 1.0), 5.0)
            object.__setattr__(target, "distance_m", float("nan"))
            return target
        return None
'''


async def test_a_processor_returning_code_gets_frame_errors_and_the_platform_runs_on(tmp_path: Path) -> None:
    (tmp_path / "hostile.py").write_text(HOSTILE)
    buffer = FrameBuffer()
    results: list[ProcessedFrame] = []
    async with running_worker("process", f"{tmp_path}/hostile.py:Hostile", results.append) as worker:
        await one_at_a_time(worker, buffer, results, 6)
        assert worker.phase == HostPhase(HostState.RUNNING)  # the same child throughout: nothing ended it
    first, second, third, *rest = results
    first, second, third = first.outcome, second.outcome, third.outcome
    assert isinstance(first.vector, str) and "Exits object" in first.vector  # its repr: the gate rejects text
    target = second.outputs.landing_target
    assert type(target).__name__ == "LandingTarget" and target.distance_m == 5.0  # its data, none of its code
    assert third.error and "could not be read" in third.error and "landing target distance" in third.error
    assert third.outputs.landing_target is None and third.vector is None  # nothing of that frame is used
    assert worker.snapshot().errors == 1
    assert all(r.outcome.vector == (0.1, 0.0, 0.5) and not r.outcome.error for r in rest)  # the junk cost no frame
